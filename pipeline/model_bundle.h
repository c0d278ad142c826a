// A trained UAVLoc model on disk, as `uavsim train` writes it and the run loop
// loads it: one folder holding
//
//   model.json            this manifest (format, provenance, sizes, file names)
//   camera.json/.pt       the camera node's IB-CC model (ib_model_io.h)
//   lidar.json/.pt        the LiDAR node's
//   radar.json/.pt        the radar node's
//   uavloc.pt/.pt.json    the edge network of the paper: TE-Align, MADW, MICA, Mamba,
//                         linear head (uavloc_model.h): method `uavloc`
//   uavloc_anchored.pt/.pt.json  the same with our anchored head (pipeline/anchored/):
//                         method `uavloc_anchored`
//   training_report.json  losses per stage and held-out RMSE (written by the trainer)
//   checksums.sha256      SHA-256 of every other file (pipeline/model_checksums.h)
//
// A model is addressed by its manifest or its folder. Torch-free header.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "pipeline/edge/edge_localizer.h"
#include "pipeline/node/node_encoder.h"
#include "pipeline/training_config.h"

namespace uavsim::pipeline {

struct ModelManifest {
  static constexpr const char* kFormat = "uavsim-model/1";
  std::string format = kFormat;
  std::string note;                    // how it was made: the train command, seed and data
  std::string scenario;                // name of the scenario it was trained for
  std::string layout_hash;             // fingerprint of that scenario's world and nodes
  int latent_dim = 16;                 // z of every node's latent
  double window_s = 0.2;               // t^w
  std::string camera = "camera.json";  // per-modality IB-CC sidecars, relative to the folder
  std::string lidar = "lidar.json";
  std::string radar = "radar.json";
  // The edge networks' weights (sidecars: + ".json"), either may be empty
  // (not trained; both: a model of stage-1 encoders only): the paper's head (`uavloc`) and the
  // anchored head (`uavloc_anchored`). Each file's sidecar says which head it holds (models written
  // before the anchored head got its own key hold it in `edge`; Load serves it as
  // `uavloc_anchored`).
  std::string edge = "uavloc.pt";
  std::string anchored_edge;
  // The variant it is (pipeline/variants.h; absent: "paper"): the
  // run loop serves its paper-layout head as the method VariantMethod(variant).
  std::string variant = "paper";
  // How it was trained, every key resolved ("training"; absent in models
  // written before the training config existed).
  std::optional<TrainingConfig> training;
};

template <class V>
void Visit(V& v, ModelManifest& c);

// The manifest a model path names: `path` itself if it is a file, or
// `path`/model.json for a folder.
std::string ModelManifestPath(const std::string& path);
// The model shipped for scenarios/default.json (in the source tree).
std::string DefaultModelPath();

// Which file of a model folder holds which edge head, read from the
// sidecars' "anchored" key (no weights loaded); empty: none. Throws
// core::ConfigError naming the file for a missing or unreadable sidecar, a
// latent size other than the manifest's, or two files of the same head.
struct EdgeHeads {
  std::string paper;     // path of the paper head's weights, or empty
  std::string anchored;  // path of the anchored head's weights, or empty
};
EdgeHeads ReadEdgeHeads(const ModelManifest& m, const std::string& manifest_path);

// Throws core::ConfigError naming the file and JSON pointer.
ModelManifest ReadModelManifest(const std::string& manifest_path);
// Writes atomically; throws std::runtime_error naming the path on failure.
void WriteModelManifest(const ModelManifest& m, const std::string& manifest_path);

// A loaded model: one encoder per modality (shared by that modality's nodes:
// the run loop is single-threaded) and its edge heads. Call InitTorch()
// first.
class UavLocModelFiles {
 public:
  // Verifies the folder's checksums.sha256 first (a changed or corrupted
  // file is refused). Throws core::ConfigError naming the file for anything missing or
  // malformed, or for a part whose latent size or modality does not match
  // the manifest.
  static std::unique_ptr<UavLocModelFiles> Load(const std::string& path);

  const ModelManifest& manifest() const { return manifest_; }
  const std::string& manifest_path() const { return manifest_path_; }
  const NodeEncoder& encoder(Modality m) const { return *encoders_[static_cast<int>(m)]; }
  const EdgeHeads& heads() const { return heads_; }
  // A fresh copy of an edge head with its own track state (the paper's, or
  // the anchored one). Throws core::ConfigError naming the manifest when the
  // model has no such head.
  std::unique_ptr<EdgeLocalizer> LoadEdge(bool anchored) const;

 private:
  ModelManifest manifest_;
  std::string manifest_path_;
  std::unique_ptr<NodeEncoder> encoders_[kModalityCount];
  EdgeHeads heads_;
};

}  // namespace uavsim::pipeline
