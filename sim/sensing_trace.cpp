#include "sim/sensing_trace.h"

#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <type_traits>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_io.h"
#include "core/sha256.h"
#include "sim/version.h"

namespace uavsim::sim {
namespace {

namespace fs = std::filesystem;
constexpr char kMagic[12] = {'U', 'A', 'V', 'S', 'I', 'M', 'T', 'R', 'A', 'C', 'E', '\0'};
enum Flags : std::uint8_t { kSight = 1, kFrameSaw = 2, kSentHolds = 4, kCamera = 8 };

// Plain little-endian values appended to a string (the machines this builds
// for are little-endian; the header's magic and version catch the rest).
class Out {
 public:
  explicit Out(std::string& s) : s_(s) {}
  template <class T>
  void Put(T v) {
    static_assert(std::is_trivially_copyable_v<T>);
    s_.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void Str(const std::string& v) {
    Put(static_cast<std::uint32_t>(v.size()));
    s_ += v;
  }
  void Floats(const std::vector<float>& v) {
    Put(static_cast<std::uint32_t>(v.size()));
    s_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float));
  }
  template <class Vec>
  void Vector(const Vec& v) {
    for (int i = 0; i < v.size(); ++i) Put(v[i]);
  }

 private:
  std::string& s_;
};

class In {
 public:
  In(const std::string& s, const std::string& path) : s_(s), path_(path) {}
  template <class T>
  T Get() {
    T v;
    Need(sizeof v);
    std::memcpy(&v, s_.data() + at_, sizeof v);
    at_ += sizeof v;
    return v;
  }
  std::string Str() {
    const auto n = Get<std::uint32_t>();
    Need(n);
    std::string v = s_.substr(at_, n);
    at_ += n;
    return v;
  }
  std::vector<float> Floats() {
    const auto n = Get<std::uint32_t>();
    Need(std::size_t{n} * sizeof(float));
    std::vector<float> v(n);
    std::memcpy(v.data(), s_.data() + at_, std::size_t{n} * sizeof(float));
    at_ += std::size_t{n} * sizeof(float);
    return v;
  }
  template <class Vec>
  void Vector(Vec& v) {
    for (int i = 0; i < v.size(); ++i) v[i] = Get<typename Vec::Scalar>();
  }
  bool AtEnd() const { return at_ == s_.size(); }

 private:
  void Need(std::size_t n) const {
    if (s_.size() - at_ < n)
      throw core::UsageError(path_ + ": a sensing trace cut short; remove it to sense again");
  }
  const std::string& s_;
  const std::string& path_;
  std::size_t at_ = 0;
};

void PutCamera(Out& o, const pipeline::CameraObservation& c) {
  o.Put(c.t_s);
  o.Put(static_cast<std::uint8_t>(c.detected));
  o.Vector(c.centre_left_px), o.Vector(c.centre_right_px);
  o.Put(c.side_left_px), o.Put(c.side_right_px);
  o.Vector(c.eye_left_w), o.Vector(c.eye_right_w);
  o.Vector(c.bearing_left_w), o.Vector(c.bearing_right_w);
}

pipeline::CameraObservation GetCamera(In& in) {
  pipeline::CameraObservation c;
  c.t_s = in.Get<double>();
  c.detected = in.Get<std::uint8_t>() != 0;
  in.Vector(c.centre_left_px), in.Vector(c.centre_right_px);
  c.side_left_px = in.Get<float>(), c.side_right_px = in.Get<float>();
  in.Vector(c.eye_left_w), in.Vector(c.eye_right_w);
  in.Vector(c.bearing_left_w), in.Vector(c.bearing_right_w);
  return c;
}

void PutPoints(Out& o, const pipeline::PointObservation& p) {
  o.Put(p.t_s);
  o.Put(static_cast<std::int32_t>(p.channels));
  o.Floats(p.values);
  o.Vector(p.sensor_position_w);
}

pipeline::PointObservation GetPoints(In& in) {
  pipeline::PointObservation p;
  p.t_s = in.Get<double>();
  p.channels = in.Get<std::int32_t>();
  p.values = in.Floats();
  in.Vector(p.sensor_position_w);
  return p;
}

std::vector<std::string> NodeIds(const Scenario& s) {
  std::vector<std::string> ids;
  for (const NodeConfig& n : s.nodes) ids.push_back(n.id);
  return ids;
}

// The resolved scenario without what cannot change what the nodes sense.
core::Json SensingPart(const Scenario& s) {
  core::Json j = ResolvedJson(s);
  for (const char* key : {"name", "links", "base_station", "outputs", "execution"}) j.erase(key);
  for (core::Json& node : j.at("nodes")) node.erase("uplink");
  core::Json& p = j.at("pipeline");
  for (const char* key : {"model", "window_s", "late_allowance_s", "methods", "scripted",
                          "uavloc_wait_for_track", "ekf"})
    p.erase(key);
  return j;
}

// The file this code was loaded from (the executable, or the Python
// module's shared object), by the mapping that holds this function.
std::string ProgramFile() {
  const auto here = reinterpret_cast<std::uintptr_t>(&ProgramFile);
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line)) {
    std::uintptr_t lo = 0, hi = 0;
    if (std::sscanf(line.c_str(), "%" SCNxPTR "-%" SCNxPTR, &lo, &hi) != 2) continue;
    const auto slash = line.find('/');
    if (here >= lo && here < hi && slash != std::string::npos) return line.substr(slash);
  }
  return "/proc/self/exe";
}

// The running program's bytes: any rebuild makes new keys, so no binary
// replays what another one sensed (the git hash alone is fixed at
// configure time and misses uncommitted changes).
const std::string& ProgramFingerprint() {
  static const std::string fingerprint = [] {
    try {
      return core::Sha256FileHex(ProgramFile());
    } catch (const std::exception&) {
      return std::string("unknown");
    }
  }();
  return fingerprint;
}

}  // namespace

std::string SensingKey(const Scenario& s, const std::string& encoders) {
  core::Json k = core::Json::object();
  k["trace_version"] = kSensingTraceVersion;
  k["uavsim"] = std::string(Version()) + " " + GitHash();
  k["program_sha256"] = ProgramFingerprint();
  k["scenario"] = SensingPart(s);
  k["encoders"] = encoders;
  if (!s.world.city.path.empty()) {
    const fs::path p = fs::path(s.base_dir) / s.world.city.path;
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) k["city_sha256"] = core::Sha256FileHex(p.string());
  }
  return core::Sha256Hex(k.dump());
}

std::string SensingTracePath(const std::string& dir, const std::string& key) {
  return (fs::path(dir) / (key + ".trace")).string();
}

SensingTraceWriter::SensingTraceWriter(std::string key, const Scenario& s)
    : key_(std::move(key)), node_ids_(NodeIds(s)) {}

void SensingTraceWriter::Add(std::uint32_t node, const TracedFrame& f) {
  Out o(bytes_);
  o.Put(std::uint8_t{1});
  o.Put(node);
  o.Put(static_cast<std::int64_t>(f.t));
  o.Put(f.raw_bytes);
  std::uint8_t flags = f.content.camera ? kCamera : 0;
  if (f.sight)
    flags |= kSight | (f.sight->frame_saw ? kFrameSaw : 0) | (f.sight->sent_holds ? kSentHolds : 0);
  o.Put(flags);
  if (f.content.camera) {
    PutCamera(o, *f.content.camera);
  } else {
    if (!f.content.points) throw std::logic_error("a traced frame without an observation");
    PutPoints(o, *f.content.points);
  }
  o.Floats(f.content.latent);
  o.Put(static_cast<std::uint32_t>(f.content.further.size()));
  for (const NodeObservation& further : f.content.further) {
    o.Put(static_cast<std::uint8_t>(further.camera ? kCamera : 0));
    if (further.camera)
      PutCamera(o, *further.camera);
    else
      PutPoints(o, *further.points);
    o.Floats(further.latent);
  }
  ++frames_;
}

void SensingTraceWriter::Write(const std::string& dir) const {
  std::string file(kMagic, sizeof kMagic);
  Out o(file);
  o.Put(kSensingTraceVersion);
  o.Str(key_);
  o.Put(static_cast<std::uint32_t>(node_ids_.size()));
  for (const std::string& id : node_ids_) o.Str(id);
  file += bytes_;
  o.Put(std::uint8_t{0});
  o.Put(frames_);
  std::error_code ec;
  fs::create_directories(dir, ec);
  core::WriteFileAtomic(SensingTracePath(dir, key_), file);
}

SensingTraceReader::SensingTraceReader(const std::string& dir, const std::string& key,
                                       const Scenario& s)
    : path_(SensingTracePath(dir, key)), frames_(s.nodes.size()) {
  std::error_code ec;
  if (!fs::is_regular_file(path_, ec))
    throw core::UsageError(path_ + ": no sensing trace for this scenario's sensing (key " +
                           key.substr(0, 16) + "...); write one with --trace " + dir);
  const std::string bytes = core::ReadFileBytes(path_);
  In in(bytes, path_);
  if (bytes.size() < sizeof kMagic || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw core::UsageError(path_ + ": not a uavsim sensing trace");
  for (std::size_t i = 0; i < sizeof kMagic; ++i) in.Get<char>();
  const auto version = in.Get<std::uint32_t>();
  if (version != kSensingTraceVersion)
    throw core::UsageError(path_ + ": a sensing trace of format version " +
                           std::to_string(version) + "; this uavsim reads version " +
                           std::to_string(kSensingTraceVersion) + " (remove it to sense again)");
  if (in.Str() != key) throw core::UsageError(path_ + ": a sensing trace of another sensing key");
  if (in.Get<std::uint32_t>() != s.nodes.size() || [&] {
        for (const std::string& id : NodeIds(s))
          if (in.Str() != id) return true;
        return false;
      }())
    throw core::UsageError(path_ + ": a sensing trace of other nodes");
  std::uint64_t count = 0;
  while (in.Get<std::uint8_t>() == 1) {
    const auto node = in.Get<std::uint32_t>();
    if (node >= frames_.size()) throw core::UsageError(path_ + ": a frame of an unknown node");
    TracedFrame f;
    f.t = in.Get<std::int64_t>();
    f.raw_bytes = in.Get<std::uint64_t>();
    const auto flags = in.Get<std::uint8_t>();
    if (flags & kSight) f.sight = TargetSight{(flags & kFrameSaw) != 0, (flags & kSentHolds) != 0};
    if (flags & kCamera)
      f.content.camera = GetCamera(in);
    else
      f.content.points = GetPoints(in);
    f.content.latent = in.Floats();
    f.content.further.resize(in.Get<std::uint32_t>());
    for (NodeObservation& further : f.content.further) {
      if (in.Get<std::uint8_t>() & kCamera)
        further.camera = GetCamera(in);
      else
        further.points = GetPoints(in);
      further.latent = in.Floats();
    }
    frames_[node].push_back(std::move(f));
    ++count;
  }
  if (in.Get<std::uint64_t>() != count || !in.AtEnd())
    throw core::UsageError(path_ + ": a sensing trace whose frame count does not match");
}

TracedFrame SensingTraceReader::Take(std::uint32_t node, core::SimTime t) {
  std::deque<TracedFrame>& q = frames_.at(node);
  if (q.empty() || q.front().t != t)
    throw std::runtime_error(path_ + ": node " + std::to_string(node) +
                             " has no frame at t = " + std::to_string(core::ToSeconds(t)) +
                             " s in this trace; it does not fit the run");
  TracedFrame f = std::move(q.front());
  q.pop_front();
  return f;
}

}  // namespace uavsim::sim
