// What a sensing node's message carries (sim/sensing_node.h makes it; the
// edge server, the training collector and sensing traces read it), apart
// from the node that makes it, so that what reads a message does not
// depend on how it is made.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "channel/packet.h"
#include "pipeline/node/observations.h"

namespace uavsim::sim {

// One observation of a message: the pre-processed measurement (for the
// edge's classical filters and the anchors) and its IB-CC latent.
struct NodeObservation {
  std::optional<pipeline::CameraObservation> camera;
  std::optional<pipeline::PointObservation> points;
  std::vector<float> latent;  // the IB-CC mu, when a model runs and something was found

  // Whether it holds anything (a detection, a point).
  bool Found() const;
  // Bytes of the pre-processed observation: the two ROI crops at 8 bits
  // plus their geometry, or the points as float32; 0 when nothing was found.
  std::uint64_t PreprocessedBytes() const;
};

// What a node's message carries besides its size, opaque to the channel:
// the observation its pre-processing picked (the one single-target methods
// see) and, with /pipeline/preprocess/max_observations > 1, the further
// ones (each found).
struct NodeContent : channel::MessageContent, NodeObservation {
  std::string node_id;
  std::vector<NodeObservation> further;
  std::size_t sample = 0;  // set by a training collector: the frame's sample index

  // Whether pre-processing found anything to send.
  bool FoundSomething() const { return Found() || !further.empty(); }
  // The observations the message carries: the picked one when found, and
  // the further ones.
  std::size_t ObservationCount() const { return (Found() ? 1 : 0) + further.size(); }
  // Of every observation the message carries.
  std::uint64_t PreprocessedBytes() const;
};

// The content a sensing node put in `m` (m.content must be set). Throws
// std::logic_error for content of another kind.
const NodeContent& ContentOf(const channel::Message& m);

// Whether a point frame saw the target and whether what the node sends
// holds it: simulator ground truth for the run's diagnostics (metrics.json's
// target_* counts), never seen by the node or the edge. A point "holds the
// target" within kTargetRadiusM of its modality of the target's position at
// the point's own time (LiDAR 1 m, radar 3 m).
struct TargetSight {
  bool frame_saw = false;   // some raw return within the radius
  bool sent_holds = false;  // the pre-processed observation has such a point
};

}  // namespace uavsim::sim
