// The model catalog: resolves the learned and TorchScript methods a
// scenario lists to their model folders, manifests and files, checks them,
// loads them and makes each method (localization_method.h). The one place
// that knows where a method's weights live: `/pipeline/model` names the
// scenario's model folder ("default": the one shipped for
// scenarios/default.json, DefaultModelPath); a variant's method (gru,
// no_mica, ...) runs the edge head of the folder beside it named
// FOLDER-VARIANT (trained with `uavsim train --variant V --encoders
// FOLDER`: the nodes' encoders are shared), or of the model itself when it
// is that variant; a TorchScript method's file is its entry's "edge".
// Relative paths resolve against the scenario's folder.
//
// Errors: core::ConfigError naming the scenario file and the JSON pointer of
// what does not fit (/pipeline/model, /pipeline/latent_dim,
// /pipeline/window_s, /pipeline/preprocess/raw, /pipeline/methods/i[/edge]).
// Determinism: loading draws nothing; call pipeline::InitTorch first.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/json_io.h"
#include "core/modality.h"
#include "pipeline/localization_method.h"
#include "pipeline/model_bundle.h"
#include "pipeline/model_resolution.h"
#include "pipeline/pipeline_config.h"

namespace uavsim::pipeline {

class NodeEncoder;

class ModelCatalog {
 public:
  // Resolves and checks every model the scenario's methods run without
  // loading weights (ResolveModels).
  explicit ModelCatalog(CatalogScenario s);
  ~ModelCatalog();
  ModelCatalog(ModelCatalog&&) noexcept;

  bool needs_model() const { return resolved_.needs_model; }
  // The scenario model's manifest (empty when no method needs a model).
  const std::string& model_path() const { return resolved_.model_path; }
  // Model folders without checksums.sha256 (older models): only loading
  // them checks their files.
  const std::vector<std::string>& unchecked() const { return resolved_.unchecked; }

  // Loads the TorchScript methods' files and checks their signatures.
  void LoadScripted();
  // Loads everything the methods run: the model, the variants' models and
  // the TorchScript files; warns on stderr (unless `quiet`) when the model
  // was trained for another world or node layout.
  void Load(bool quiet);

  // The model's IB-CC encoder of modality m (null before Load or without a model).
  const NodeEncoder* encoder(core::Modality m) const;
  // metrics.json's "uavloc_model" (path, trained_for, same_layout, heads,
  // extensions, temporal, variant, variants, scripted); null before Load or
  // without a model.
  const core::Json& info() const { return info_; }

  // The learned or TorchScript method `name` with its own state (a learned
  // one a fresh copy of its edge head; a TorchScript one its loaded file,
  // handed over: once per name); null for a method of no model (ekf,
  // anchor_track). After Load.
  std::unique_ptr<LocalizationMethod> MakeMethod(const std::string& name);

 private:
  CatalogScenario s_;
  ModelResolution resolved_;
  std::unique_ptr<UavLocModelFiles> model_;
  std::map<std::string, std::unique_ptr<UavLocModelFiles>> variant_models_;
  std::map<std::string, std::unique_ptr<ScriptedEdge>> scripted_;
  core::Json info_;
};

}  // namespace uavsim::pipeline
