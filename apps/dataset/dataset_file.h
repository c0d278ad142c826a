// The HDF5 file of `uavsim dataset` (apps/dataset/dataset_export.h; the schema in full
// is docs/dataset.md): the one file of uavsim that talks to HDF5.
//
//   /                 attributes: the provenance (DatasetHeader)
//   /nodes            the scenario's sensing nodes (row = node index)
//   /episodes/NNNNNN  one group per episode: window_truth_m, frames/,
//                     camera/, lidar/, radar/
//
// Units are SI: world ENU metres, simulated seconds. Large arrays (camera
// crops, point clouds, latents) are chunked and compressed (gzip level 4
// with the shuffle filter); empty arrays are written with a zero first
// dimension. No object carries a time stamp (H5Pset_obj_track_times off),
// so the same contents give the same file byte for byte.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "pipeline/training/dataset.h"

namespace uavsim::sim {

// The root group's attributes.
struct DatasetHeader {
  static constexpr std::int64_t kSchemaVersion = 1;
  std::string uavsim_version;  // sim/version.h
  std::string uavsim_git_hash;
  std::string scenario_file;    // as given on the command line
  std::string scenario;         // the resolved scenario, JSON text
  std::uint64_t seed = 1;       // the episode plan's seed (uavsim dataset --seed)
  double episode_s = 0.0;       // simulated seconds of each episode
  double window_s = 0.2;        // the alignment window t^w
  std::int64_t latent_dim = 0;  // 0: no latents
  std::string model;            // the model's manifest path, "" without
  // Per episode, the part `uavsim train --seed seed` puts it in by
  // trajectory: 0 training, 1 validation, 2 test (empty: no `part`
  // attribute is written).
  std::vector<int> parts;
};

// One row of /nodes.
struct DatasetNode {
  std::string id;
  core::Modality modality = core::Modality::kCamera;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // the sensor pose's position, world ENU
  Eigen::Vector3d rpy_deg = Eigen::Vector3d::Zero();     // its roll, pitch, yaw (DESIGN.md)
  double rate_hz = 0.0;                                  // frames per second
};

// Writes the file at `path` (created or truncated; the caller makes it
// atomic). `latents` is empty (no model: no latent datasets) or holds, per
// episode, one latent of `header.latent_dim` values per sample. Throws
// std::invalid_argument naming `path` for contents that do not fit the
// schema (a camera crop other than 128 x 128, a point cloud whose channels
// differ from its modality's, a sample's node outside `nodes`, latents of
// another count or size), std::runtime_error naming `path` when HDF5 fails.
// `episode_written` (may be empty) is called after each episode with the
// count so far; what it throws propagates (the file is then incomplete).
void WriteDatasetFile(const std::string& path, const DatasetHeader& header,
                      const std::vector<DatasetNode>& nodes,
                      const std::vector<pipeline::Episode>& episodes,
                      const std::vector<std::vector<std::vector<float>>>& latents,
                      const std::function<void(std::size_t)>& episode_written = {});

}  // namespace uavsim::sim
