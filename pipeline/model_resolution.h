// Finding and checking the trained models a scenario's methods run, without
// loading a weight (and without LibTorch: `uavsim validate` runs this in a
// program that does not load it): the scenario's model folder and its
// variants' folders, their manifests, checksums, heads and settings. The
// model catalog (model_catalog.h) loads what this finds.
//
// Errors: core::ConfigError naming the scenario file and the JSON pointer of
// what does not fit (/pipeline/model, /pipeline/latent_dim,
// /pipeline/window_s, /pipeline/preprocess/raw, /pipeline/methods/i).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "pipeline/model_bundle.h"
#include "pipeline/pipeline_config.h"

namespace uavsim::pipeline {

// What of a scenario the catalog reads.
struct CatalogScenario {
  const PipelineConfig* pipeline = nullptr;
  std::string base_dir;     // the scenario file's folder: relative paths start here
  std::string file;         // the scenario file errors name
  std::string layout_hash;  // the scenario's world and node layout (a model's "layout_hash")
};

// Whether the scenario runs a method that needs a trained model (uavloc and
// its variants and subsets, uavloc_anchored, TorchScript and Python methods: they run
// on the model's latents).
bool NeedsTrainedModel(const PipelineConfig& p);

// Whether the nodes send geometric anchors with their latents: a method that
// reads them runs (uavloc_anchored, anchor_track).
bool SendsAnchors(const PipelineConfig& p);

// The manifest path of a model folder given on a command line (`--model
// DIR`, "default": the shipped one unless a folder of that name exists),
// checked as CheckEncoderModel (sim/edge_server.h) says.
std::string ResolveEncoderModel(const CatalogScenario& s, const std::string& dir,
                                const std::string& command);

// The models a scenario's methods run, found and checked.
struct ModelResolution {
  bool needs_model = false;
  std::string model_path;  // the scenario model's manifest (empty: no method needs one)
  ModelManifest manifest;
  std::map<std::string, std::string> variant_paths;  // variant -> manifest
  // Model folders without checksums.sha256 (older models): only loading
  // them checks their files.
  std::vector<std::string> unchecked;
};

// Resolves and checks every model the scenario's methods run without
// loading weights: the model's manifest parses, its folder's checksums
// hold, it has each method's edge head, its latent size and window length
// are the scenario's, a raw-variant model meets raw pre-processing, and
// each variant's folder is that variant with the same encoders. Nothing
// when no method needs a model. (TorchScript methods' files are checked by
// loading them: ModelCatalog::LoadScripted.)
ModelResolution ResolveModels(const CatalogScenario& s);

// How to make a model that fits, for error messages.
extern const char* const kHowToTrain;

// The variant a learned method runs ("paper" for uavloc).
std::string VariantOfMethod(const std::string& learned);

}  // namespace uavsim::pipeline
