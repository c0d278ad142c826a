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
// run (core/atomic_file.h), as records that each carry a CRC-32 (zlib's)
// over their own bytes, and a SHA-256 over the whole file, written last:
//   header: "UAVSIMTRACE\0" | u32 version | u32 size | str key | u32 nodes |
//           str id per node | u32 crc
//   frame:  u8 1 | u32 size | u32 node | i64 t_ns | u64 raw_bytes | u8 flags |
//           observation | u32 n | f32 latent[n] |
//           u32 further | per further observation: u8 flags | observation |
//           u32 n | f32 latent[n] | u32 crc
//   end:    u8 0 | u32 size | u64 frame count | u32 crc
//   digest: 64 hex digits, the SHA-256 of every byte before them
// (size: the bytes between it and the crc; crc: over the record's bytes
// before it; str: u32 length and bytes; flags: 1 sight, 2 frame saw the
// target, 4 what was sent holds it, 8 a camera observation; the camera
// observation without its crops, which never travel). A replay uses no
// byte before every record's CRC and the digest have been checked: a
// trace copied between machines or damaged on disk is refused, naming its
// first bad record, never replayed.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "core/time.h"
#include "sim/node_content.h"
#include "sim/scenario.h"

namespace uavsim::sim {

inline constexpr std::uint32_t kSensingTraceVersion = 3;

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

// Each node's frames in send order.
using TracedFrames = std::vector<std::deque<TracedFrame>>;

// Checks and reads the bytes of a trace file (`path` names it in errors)
// that should hold `key`'s sensing by nodes `node_ids`. Throws
// core::UsageError naming `path` when it is not a trace, of another format
// version, for another key or node list, cut short, or corrupt: a record
// whose CRC-32 fails (named by its place: "the header", "record N", the
// frames from 1 and the end record last, and its first byte),
// a digest that does not match, a record whose content is malformed.
// Never reads outside `bytes`.
TracedFrames ParseSensingTrace(const std::string& bytes, const std::string& path,
                               const std::string& key, const std::vector<std::string>& node_ids);

// A trace file read back.
class SensingTraceReader {
 public:
  // Reads DIR/<key>.trace (ParseSensingTrace). Throws core::UsageError
  // naming the file when it is missing or refused.
  SensingTraceReader(const std::string& dir, const std::string& key, const Scenario& s);
  // Node `node`'s next frame, which must be at time t (else
  // std::runtime_error naming the file: the trace does not fit the run).
  TracedFrame Take(std::uint32_t node, core::SimTime t);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  TracedFrames frames_;
};

}  // namespace uavsim::sim
