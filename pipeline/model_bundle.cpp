#include "pipeline/model_bundle.h"

#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "core/error.h"
#include "pipeline/model_checksums.h"

namespace uavsim::pipeline {
namespace fs = std::filesystem;

std::unique_ptr<UavLocModelFiles> UavLocModelFiles::Load(const std::string& path) {
  auto files = std::make_unique<UavLocModelFiles>();
  files->manifest_path_ = ModelManifestPath(path);
  const fs::path folder = fs::path(files->manifest_path_).parent_path();
  VerifyModelChecksums(folder.empty() ? "." : folder.string());
  files->manifest_ = ReadModelManifest(files->manifest_path_);
  const ModelManifest& m = files->manifest_;
  const auto require = [&](const std::string& name, const char* key) {
    const fs::path p = folder / name;
    std::error_code ec;
    if (!fs::is_regular_file(p, ec))
      throw core::ConfigError(files->manifest_path_, std::string("/") + key,
                              "file not found: " + p.string());
    return p.string();
  };
  const std::pair<Modality, const char*> parts[] = {
      {Modality::kCamera, "camera"}, {Modality::kLidar, "lidar"}, {Modality::kRadar, "radar"}};
  for (const auto& [modality, key] : parts) {
    const std::string& name = modality == Modality::kCamera  ? m.camera
                              : modality == Modality::kLidar ? m.lidar
                                                             : m.radar;
    const std::string sidecar = require(name, key);
    std::unique_ptr<NodeEncoder> enc;
    try {
      enc = NodeEncoder::Load(sidecar);
    } catch (const std::runtime_error& e) {
      if (dynamic_cast<const core::ConfigError*>(&e)) throw;
      throw core::ConfigError(sidecar, "", e.what());
    }
    if (enc->modality() != modality)
      throw core::ConfigError(
          sidecar, "/config/modality",
          std::string("expected the ") + key + " model, got " + ModalityName(enc->modality()));
    if (enc->latent_dim() != m.latent_dim)
      throw core::ConfigError(sidecar, "/config/latent_dim",
                              "expected " + std::to_string(m.latent_dim) + " as in " +
                                  files->manifest_path_ + ", got " +
                                  std::to_string(enc->latent_dim()));
    files->encoders_[static_cast<int>(modality)] = std::move(enc);
  }
  files->heads_ = ReadEdgeHeads(m, files->manifest_path_);
  return files;
}

std::unique_ptr<EdgeLocalizer> UavLocModelFiles::LoadEdge(bool anchored) const {
  const std::string& path = anchored ? heads_.anchored : heads_.paper;
  if (path.empty())
    throw core::ConfigError(
        manifest_path_, anchored ? "/anchored_edge" : "/edge",
        std::string("the model has no ") +
            (anchored ? "anchored head (`uavloc_anchored`)" : "paper head (`uavloc`)") +
            ": train one with `uavsim train --head both`");
  auto edge = EdgeLocalizer::Load(path);
  if (edge->anchored() != anchored)
    throw core::ConfigError(path + ".json", "/anchored", "the head changed since the model loaded");
  return edge;
}

}  // namespace uavsim::pipeline
