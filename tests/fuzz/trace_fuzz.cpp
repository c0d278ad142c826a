// libFuzzer target: the sensing-trace reader, sim::ParseSensingTrace
// (sim/sensing_trace.h, whose top comment has the file format). The first
// input byte is the mode, the rest the trace file:
//   bit 0 clear  the bytes as they are: exercises the integrity checks
//                (magic, version, record sizes, CRC-32s, digest)
//   bit 0 set    resealed: the harness walks the record layout and sets the
//                version to this build's, every record's CRC-32 and the
//                trailing SHA-256 (stopping where a size runs off the end),
//                so that the fuzzed content reaches the content parser
//                (header, frames, observations, further observations, count)
//   bit 1 set    the expected key and node ids are fixed (kKey, kNodes), so
//                the input's own header is fuzzed against them
//   bit 1 clear  they are read from the input's own header (any real trace
//                parses; the fixed ones when the header cannot be read)
// A refusal is a core::UsageError whose message starts with the path; any
// other exception, a sanitizer report or a crash is a finding. A trace the
// reader accepts is written again by sim::SensingTraceWriter and read back:
// it must be accepted and write the same bytes again.
//
// UAVSIM_FUZZ_WRITE_SEEDS=DIR build-fuzz/trace_fuzz writes seed traces made
// by this build's SensingTraceWriter into DIR and exits (scripts/fuzz does
// it on every run, so the seeds always have the current format).
#include <unistd.h>
#include <zlib.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <typeinfo>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/sha256.h"
#include "fuzz_support.h"
#include "sim/sensing_trace.h"

namespace {

namespace fs = std::filesystem;
using namespace uavsim;

constexpr char kPath[] = "fuzz.trace";
const std::string kKey(64, 'a');
const std::vector<std::string> kNodes{"cam1", "lidar1", "radar1"};
constexpr std::size_t kMagicBytes = 12;
constexpr std::size_t kHeaderPrefix = kMagicBytes + 4;  // magic, u32 version
constexpr std::uint8_t kResealed = 1, kFixedIds = 2;

// A folder of this process's own for the round trip's files.
const fs::path& Scratch() {
  static const fs::path dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    fs::path d =
        fs::path(tmp && *tmp ? tmp : "/tmp") / ("uavsim-trace-fuzz-" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  // Removed at exit (registered after `dir` is made, so it runs before
  // `dir` is destroyed); a crash leaves it for the post-mortem.
  static const bool removed_at_exit = (std::atexit([] {
                                         std::error_code ec;
                                         fs::remove_all(Scratch(), ec);
                                       }),
                                       true);
  (void)removed_at_exit;
  return dir;
}

std::uint32_t GetU32(const std::string& s, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, s.data() + at, sizeof v);
  return v;
}

void SetU32(std::string& s, std::size_t at, std::uint32_t v) {
  std::memcpy(s.data() + at, &v, sizeof v);
}

std::uint32_t Crc32(std::string_view bytes) {
  return static_cast<std::uint32_t>(crc32(crc32(0L, Z_NULL, 0),
                                          reinterpret_cast<const Bytef*>(bytes.data()),
                                          static_cast<uInt>(bytes.size())));
}

// Sets the CRC-32 of the record at `at` whose u32 size follows `prefix`
// bytes; returns where the next record starts, or npos when the record runs
// off the end of `f`.
std::size_t SealRecord(std::string& f, std::size_t at, std::size_t prefix) {
  if (f.size() - at < prefix + 4) return std::string::npos;
  const std::size_t crc_at = at + prefix + 4 + GetU32(f, at + prefix);
  if (crc_at > f.size() || f.size() - crc_at < 4) return std::string::npos;
  SetU32(f, crc_at, Crc32(std::string_view(f).substr(at, crc_at - at)));
  return crc_at + 4;
}

// Makes `f` pass the reader's integrity checks as far as its layout goes:
// this build's version, every whole record's CRC-32 and, after the end
// record, the SHA-256 of everything before it in place of the rest.
std::string Reseal(std::string f) {
  if (f.size() < kHeaderPrefix) return f;
  SetU32(f, kMagicBytes, sim::kSensingTraceVersion);
  std::size_t at = SealRecord(f, 0, kHeaderPrefix);
  while (at != std::string::npos && at < f.size()) {
    const auto tag = static_cast<std::uint8_t>(f[at]);
    if (tag > 1) break;  // refused as of no known kind: nothing more to seal
    at = SealRecord(f, at, 1);
    if (tag == 0 && at != std::string::npos) {
      f.resize(at);
      f += core::Sha256Hex(f);
      break;
    }
  }
  return f;
}

// The key and node ids in the header of `f`, read without any check; false
// when it does not hold them.
bool HeaderIds(const std::string& f, std::string* key, std::vector<std::string>* nodes) {
  std::size_t at = kHeaderPrefix + 4;
  const auto str = [&](std::string* out) {
    if (f.size() < at || f.size() - at < 4) return false;
    const std::uint32_t n = GetU32(f, at);
    at += 4;
    if (f.size() - at < n) return false;
    out->assign(f, at, n);
    at += n;
    return true;
  };
  if (!str(key) || f.size() - at < 4) return false;
  const std::uint32_t count = GetU32(f, at);
  at += 4;
  if (count > f.size()) return false;  // each id takes 4 bytes at least
  nodes->resize(count);
  for (std::string& id : *nodes)
    if (!str(&id)) return false;
  return true;
}

// What the reader gives back must be what it documents: one list per node,
// each frame with exactly one observation, point clouds of 1-16 channels.
void CheckFrames(const sim::TracedFrames& frames, std::size_t nodes) {
  if (frames.size() != nodes) fuzz::Finding("frames of another node count", "");
  const auto check = [](const sim::NodeObservation& o) {
    if (o.camera.has_value() == o.points.has_value())
      fuzz::Finding("an observation that is not exactly one of camera and points", "");
    if (o.points && (o.points->channels < 1 || o.points->channels > 16 ||
                     o.points->values.size() % o.points->channels != 0))
      fuzz::Finding("a point observation of bad shape", std::to_string(o.points->channels));
  };
  for (const auto& node : frames)
    for (const sim::TracedFrame& f : node) {
      check(f.content);
      for (const sim::NodeObservation& o : f.content.further) check(o);
    }
}

// `frames` written by SensingTraceWriter under kKey (node by node), as bytes.
std::string WriteTrace(const sim::TracedFrames& frames, const std::vector<std::string>& ids) {
  sim::Scenario s;
  s.nodes.clear();
  for (const std::string& id : ids) s.nodes.push_back({id, {}, "default"});
  sim::SensingTraceWriter w(kKey, s);
  for (std::size_t n = 0; n < frames.size(); ++n)
    for (const sim::TracedFrame& f : frames[n]) w.Add(static_cast<std::uint32_t>(n), f);
  w.Write(Scratch().string());
  return core::ReadFileBytes(sim::SensingTracePath(Scratch().string(), kKey));
}

// An accepted trace, written again and read back, is accepted and writes
// the same bytes: the writer and the reader agree on every field.
void RoundTrip(const sim::TracedFrames& frames, const std::vector<std::string>& ids) {
  const std::string once = WriteTrace(frames, ids);
  sim::TracedFrames again;
  try {
    again = sim::ParseSensingTrace(once, "rewritten.trace", kKey, ids);
  } catch (const std::exception& e) {
    fuzz::Finding("the rewritten trace is refused", e.what());
  }
  if (WriteTrace(again, ids) != once)
    fuzz::Finding("the rewritten trace reads back to other frames", "");
}

// Parses `file` expecting `key` and `ids`: returns normally when it is
// accepted (and round-trips) or refused as documented, aborts otherwise.
void Parse(const std::string& file, const std::string& key, const std::vector<std::string>& ids) {
  sim::TracedFrames frames;
  try {
    frames = sim::ParseSensingTrace(file, kPath, key, ids);
  } catch (const core::UsageError& e) {
    static const bool verbose = std::getenv("UAVSIM_FUZZ_VERBOSE") != nullptr;
    if (verbose) std::fprintf(stderr, "refused: %s\n", e.what());
    if (std::string_view(e.what()).rfind(std::string(kPath) + ": ", 0) != 0)
      fuzz::Finding("a refusal that does not start with the path", e.what());
    return;
  } catch (const std::exception& e) {
    fuzz::Finding(typeid(e).name(), e.what());
  } catch (...) {
    fuzz::Finding("unknown exception", "");
  }
  CheckFrames(frames, ids.size());
  RoundTrip(frames, ids);
}

// Seeds: traces by this build's writer under kKey and kNodes.
sim::TracedFrame PointFrame(core::SimTime t, int channels, int points, std::size_t further) {
  sim::TracedFrame f;
  f.t = t;
  f.raw_bytes = 1000 + static_cast<std::uint64_t>(t % 997);
  f.sight = sim::TargetSight{true, points > 0};
  pipeline::PointObservation p;
  p.t_s = static_cast<double>(t) * 1e-9;
  p.channels = channels;
  for (int i = 0; i < points * channels; ++i) p.values.push_back(0.25f * static_cast<float>(i));
  p.sensor_position_w = {30.0, -30.0, 1.5};
  f.content.points = p;
  f.content.latent.assign(16, 0.5f);
  for (std::size_t k = 0; k < further; ++k) {
    sim::NodeObservation o;
    o.points = p;
    o.latent.assign(16, -0.5f);
    f.content.further.push_back(o);
  }
  return f;
}

sim::TracedFrame CameraFrame(core::SimTime t, bool detected, std::size_t further) {
  sim::TracedFrame f;
  f.t = t;
  f.raw_bytes = 640 * 480 * 2;
  pipeline::CameraObservation c;
  c.t_s = static_cast<double>(t) * 1e-9;
  c.detected = detected;
  c.centre_left_px = {320.5f, 200.25f};
  c.centre_right_px = {300.5f, 200.25f};
  c.side_left_px = c.side_right_px = 32.0f;
  c.eye_right_w = {0.12, 0.0, 0.0};
  f.content.camera = c;
  if (detected) f.content.latent.assign(16, 0.125f);
  for (std::size_t k = 0; k < further; ++k) {
    sim::NodeObservation o;
    o.camera = c;
    o.latent.assign(16, 0.75f);
    f.content.further.push_back(o);
  }
  return f;
}

void WriteSeed(const std::string& dir, const std::string& name,
               const std::vector<std::pair<std::uint32_t, sim::TracedFrame>>& frames) {
  sim::Scenario s;
  s.nodes.clear();
  for (const std::string& id : kNodes) s.nodes.push_back({id, {}, "default"});
  sim::SensingTraceWriter w(kKey, s);
  for (const auto& [node, f] : frames) w.Add(node, f);
  w.Write(Scratch().string());
  const std::string bytes = core::ReadFileBytes(sim::SensingTracePath(Scratch().string(), kKey));
  for (const int mode : {0, int{kResealed}, kResealed | kFixedIds})
    core::WriteFileAtomic((fs::path(dir) / (name + "-mode" + std::to_string(mode))).string(),
                          std::string(1, static_cast<char>(mode)) + bytes);
}

void WriteSeeds(const std::string& dir) {
  fs::create_directories(dir);
  WriteSeed(dir, "empty", {});
  WriteSeed(dir, "three_nodes",
            {{0, CameraFrame(0, false, 0)},
             {1, PointFrame(1000000, 4, 3, 0)},
             {2, PointFrame(2000000, 5, 2, 0)},
             {0, CameraFrame(33333333, true, 0)}});
  WriteSeed(
      dir, "max_observations",
      {{0, CameraFrame(0, true, 2)}, {1, PointFrame(0, 4, 1, 3)}, {2, PointFrame(0, 5, 4, 1)}});
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* dir = std::getenv("UAVSIM_FUZZ_WRITE_SEEDS")) {
    WriteSeeds(dir);
    std::exit(0);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::uint8_t mode = data[0];
  std::string file(reinterpret_cast<const char*>(data) + 1, size - 1);
  if (mode & kResealed) file = Reseal(std::move(file));
  std::string key = kKey;
  std::vector<std::string> ids = kNodes;
  if (!(mode & kFixedIds) && !HeaderIds(file, &key, &ids)) key = kKey, ids = kNodes;
  Parse(file, key, ids);
  return 0;
}
