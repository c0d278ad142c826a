// The model manifest and its edge heads' sidecars (model_bundle.h): torch-
// free, so that the fuzz target of the model readers links without
// LibTorch (tests/fuzz/).
#include "pipeline/model_bundle.h"

#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_io.h"
#include "pipeline/variants.h"

#ifndef UAVSIM_MODELS_DIR
#error "UAVSIM_MODELS_DIR must name the source tree's models/ folder"
#endif

namespace uavsim::pipeline {
namespace {

namespace fs = std::filesystem;

bool IsPlainFileName(const std::string& name) {
  return !name.empty() && fs::path(name).filename() == fs::path(name);
}

}  // namespace

template <class V>
void Visit(V& v, ModelManifest& c) {
  v("format", c.format);
  v.Check(c.format == ModelManifest::kFormat, "format",
          std::string("expected \"") + ModelManifest::kFormat + "\", got \"" + c.format + "\"");
  v("note", c.note);
  v("scenario", c.scenario);
  v("layout_hash", c.layout_hash);
  v("latent_dim", c.latent_dim, core::Rule::Range(2, 4096));
  v("window_s", c.window_s, core::Rule::Range(1e-9, 3600.0));
  for (auto [key, name] : {std::pair{"camera", &c.camera}, std::pair{"lidar", &c.lidar},
                           std::pair{"radar", &c.radar}}) {
    v(key, *name);
    v.Check(IsPlainFileName(*name), key,
            "expected a file name in the model's folder, got \"" + *name + "\"");
  }
  // The edge heads: either may be empty; both empty is a model of stage-1
  // encoders only (`uavsim train --head none`), which no method can run.
  for (auto [key, name] :
       {std::pair{"edge", &c.edge}, std::pair{"anchored_edge", &c.anchored_edge}}) {
    v(key, *name);
    v.Check(name->empty() || IsPlainFileName(*name), key,
            "expected a file name in the model's folder or \"\", got \"" + *name + "\"");
  }
  v("variant", c.variant);
  v.Check(FindVariant(c.variant) != nullptr, "variant",
          "expected one of " + VariantNames() + ", got \"" + c.variant + "\"");
  v.Check(c.variant == "paper" || c.anchored_edge.empty(), "anchored_edge",
          "only the paper variant has the anchored head, this model is \"" + c.variant + "\"");
  if constexpr (V::kReading) {
    if (v.Has("training")) v.Object("training", c.training.emplace(EarlierModelsTrainingConfig()));
  } else if (c.training) {
    v.Object("training", *c.training);
  }
}
UAVSIM_INSTANTIATE_VISIT(ModelManifest);

std::string ModelManifestPath(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return (fs::path(path) / "model.json").string();
  return path;
}

std::string DefaultModelPath() { return std::string(UAVSIM_MODELS_DIR) + "/default/model.json"; }

ModelManifest ReadModelManifest(const std::string& manifest_path) {
  ModelManifest m;
  core::FromJson(core::LoadJsonFile(manifest_path), manifest_path, "", m);
  return m;
}

void WriteModelManifest(const ModelManifest& m, const std::string& manifest_path) {
  core::WriteFileAtomic(manifest_path, core::ToJson(m).dump(2) + "\n");
}

EdgeHeads ReadEdgeHeads(const ModelManifest& m, const std::string& manifest_path) {
  const fs::path folder = fs::path(manifest_path).parent_path();
  EdgeHeads heads;
  for (auto [key, name] :
       {std::pair{"edge", &m.edge}, std::pair{"anchored_edge", &m.anchored_edge}}) {
    if (name->empty()) continue;
    const std::string weights = (folder / *name).string();
    const std::string sidecar = weights + ".json";
    std::error_code ec;
    if (!fs::is_regular_file(weights, ec) || !fs::is_regular_file(sidecar, ec))
      throw core::ConfigError(manifest_path, std::string("/") + key,
                              "file not found: " + weights + " (and its sidecar " + sidecar + ")");
    const core::Json j = core::LoadJsonFile(sidecar);
    if (!j.is_object() || (j.contains("anchored") && !j["anchored"].is_boolean()))
      throw core::ConfigError(sidecar, "/anchored", "expected true or false");
    const bool anchored = j.value("anchored", false);
    if (!j.contains("latent_dim") || !j["latent_dim"].is_number_integer() ||
        j["latent_dim"].get<int>() != m.latent_dim)
      throw core::ConfigError(sidecar, "/latent_dim",
                              "expected " + std::to_string(m.latent_dim) + " as in " +
                                  manifest_path + ", got " +
                                  (j.contains("latent_dim") ? j["latent_dim"].dump() : "nothing"));
    std::string& slot = anchored ? heads.anchored : heads.paper;
    if (!slot.empty())
      throw core::ConfigError(manifest_path, std::string("/") + key,
                              std::string("two edge networks with the ") +
                                  (anchored ? "anchored" : "paper's") + " head: " + slot + " and " +
                                  weights);
    slot = weights;
  }
  return heads;
}

}  // namespace uavsim::pipeline
