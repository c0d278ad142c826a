// Sensing traces (issue 44): what a run's sensing nodes produced, kept so
// that a later run with the same sensing replays it instead of sensing.
//
// A node's frames depend on nothing downstream of it (sim/sensing_node.h:
// the world is a function of time; the sensor, its pre-processing, its
// encoder and its noise stream are the node's own), so a run that differs
// only in its uplinks, edge methods, beams or outputs gets from a trace the
// very messages it would have made: its outputs are the same, byte for byte
// (wall times aside).
//
// The sensing key: SHA-256 over the trace format, this build's version and
// git hash and the running program's own bytes (the executable's, or the
// Python module's; any rebuild makes new keys), and the resolved scenario without what cannot
// change sensing
// (/name, /links, /base_station, /outputs, /execution, each node's
// /uplink, /pipeline's methods and edge settings; /pipeline/model as a
// path), plus the bytes of the city mesh and of the model folder whose
// encoders the nodes run ("none" when no method needs a model). Weather is
// in it whole: rain changes the sensors as well as the links.
//
// File DIR/<key>.trace, little-endian, written all at once at the end of a
// run (core/atomic_file.h):
//   "UAVSIMTRACE\0" | u32 version | str key | u32 nodes | str id per node |
//   frames: u8 1 | u32 node | i64 t_ns | u64 raw_bytes | u8 flags |
//           observation | u32 n | f32 latent[n] |
//           u32 further | per further observation: u8 flags | observation |
//           u32 n | f32 latent[n]
//   end:    u8 0 | u64 frame count
// (str: u32 length and bytes; flags: 1 sight, 2 frame saw the target,
// 4 what was sent holds it, 8 a camera observation; the camera observation
// without its crops, which never travel).
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "core/time.h"
#include "sim/scenario.h"
#include "sim/sensing_node.h"

namespace uavsim::sim {

inline constexpr std::uint32_t kSensingTraceVersion = 2;

// One frame as its node sent it: the frame's time, its raw size, the
// simulator's ground truth about it and the content (latent included,
// camera crops cleared).
struct TracedFrame {
  core::SimTime t = 0;
  std::uint64_t raw_bytes = 0;
  std::optional<TargetSight> sight;
  NodeContent content;
};

// The sensing key of `s` (64 hex digits). `encoders`: the fingerprint of
// the encoders its nodes run (sim/edge_server.h: EncoderFingerprint).
// Throws std::runtime_error if the city mesh cannot be read.
std::string SensingKey(const Scenario& s, const std::string& encoders);

// DIR/<key>.trace.
std::string SensingTracePath(const std::string& dir, const std::string& key);

// Collects a run's frames in the order the nodes send them, then writes the
// trace file.
class SensingTraceWriter {
 public:
  SensingTraceWriter(std::string key, const Scenario& s);
  void Add(std::uint32_t node, const TracedFrame& frame);
  // Writes DIR/<key>.trace atomically (DIR made if missing). Throws
  // std::runtime_error naming the file on failure.
  void Write(const std::string& dir) const;

 private:
  std::string bytes_;  // the frames so far
  std::string key_;
  std::vector<std::string> node_ids_;
  std::uint64_t frames_ = 0;
};

// A trace file read back, each node's frames in send order.
class SensingTraceReader {
 public:
  // Reads DIR/<key>.trace. Throws core::UsageError naming the file when
  // it is missing, of another format version, for another key or node
  // list, or cut short.
  SensingTraceReader(const std::string& dir, const std::string& key, const Scenario& s);
  // Node `node`'s next frame, which must be at time t (else
  // std::runtime_error naming the file: the trace does not fit the run).
  TracedFrame Take(std::uint32_t node, core::SimTime t);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::vector<std::deque<TracedFrame>> frames_;
};

}  // namespace uavsim::sim
