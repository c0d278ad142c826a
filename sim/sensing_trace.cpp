#include "sim/sensing_trace.h"

#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string_view>
#include <type_traits>

#include <zlib.h>

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

// Reads a record's content; running past it is a malformed record (its CRC
// held, so the writer and this reader disagree: a trace of another build).
class In {
 public:
  In(std::string_view s, const std::string& what) : s_(s), what_(what) {}
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
    std::string v(s_.substr(at_, n));
    at_ += n;
    return v;
  }
  std::vector<float> Floats() {
    const auto n = Get<std::uint32_t>();
    Need(std::size_t{n} * sizeof(float));
    std::vector<float> v(n);
    if (n > 0) std::memcpy(v.data(), s_.data() + at_, std::size_t{n} * sizeof(float));
    at_ += std::size_t{n} * sizeof(float);
    return v;
  }
  template <class Vec>
  void Vector(Vec& v) {
    for (int i = 0; i < v.size(); ++i) v[i] = Get<typename Vec::Scalar>();
  }
  bool AtEnd() const { return at_ == s_.size(); }
  std::size_t Left() const { return s_.size() - at_; }
  [[noreturn]] void Malformed() const {
    throw core::UsageError(what_ + " is malformed; remove it to sense again");
  }

 private:
  void Need(std::size_t n) const {
    if (s_.size() - at_ < n) Malformed();
  }
  std::string_view s_;
  const std::string& what_;
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
  if (p.channels < 1 || p.channels > 16 || p.values.size() % p.channels != 0) in.Malformed();
  in.Vector(p.sensor_position_w);
  return p;
}

std::uint32_t Crc32(std::string_view bytes) {
  // Records stay far below zlib's 4 GiB a call.
  return static_cast<std::uint32_t>(crc32(crc32(0L, Z_NULL, 0),
                                          reinterpret_cast<const Bytef*>(bytes.data()),
                                          static_cast<uInt>(bytes.size())));
}

// Appends a record to `file`: its prefix (tag, or magic and version), the
// size of `body`, `body`, and the CRC-32 of all three.
void PutRecord(std::string& file, std::string_view prefix, const std::string& body) {
  const std::size_t at = file.size();
  file += prefix;
  Out o(file);
  o.Put(static_cast<std::uint32_t>(body.size()));
  file += body;
  o.Put(Crc32(std::string_view(file).substr(at)));
}

constexpr std::size_t kDigestChars = 64;
constexpr std::size_t kHeaderPrefix = sizeof kMagic + sizeof(std::uint32_t);

// One record of a trace file: where it starts, its tag (1 frame, 0 end;
// the header has none) and its body.
struct Record {
  std::size_t at = 0;
  std::uint8_t tag = 0;
  std::string_view body;
};

// "the header (byte 0)", "record 12 (byte 3456)": records are numbered
// from the header's 0 by their place in the file, which a damaged tag or
// size does not change.
std::string RecordName(std::size_t index, std::size_t at) {
  return (index == 0 ? std::string("the header") : "record " + std::to_string(index)) + " (byte " +
         std::to_string(at) + ")";
}

// Splits `bytes` (magic and version already checked) into its records up
// to the end record, checking each one's CRC-32. Throws core::UsageError
// naming `path` and the first record that is cut short or fails its CRC.
std::vector<Record> SplitRecords(std::string_view bytes, const std::string& path) {
  std::vector<Record> records;
  std::size_t at = 0;
  while (records.empty() || records.back().tag == 1) {
    const bool header = records.empty();
    const std::size_t prefix = header ? kHeaderPrefix : 1;
    const std::string name = RecordName(records.size(), at);
    if (at == bytes.size())
      throw core::UsageError(path + ": a sensing trace cut short before " + name +
                             "; remove it to sense again");
    const std::uint8_t tag = header ? 1 : static_cast<std::uint8_t>(bytes[at]);
    if (!header && tag > 1)
      throw core::UsageError(path + ": a corrupt sensing trace: " + name +
                             " is of no known kind; remove it to sense again");
    std::uint32_t size = 0;
    const auto cut = [&](std::size_t need) {
      if (bytes.size() - at < need)
        throw core::UsageError(path + ": a sensing trace cut short in " + name +
                               " (or that record's size is corrupt); remove it to sense again");
    };
    cut(prefix + sizeof size);
    std::memcpy(&size, bytes.data() + at + prefix, sizeof size);
    const std::size_t body_at = at + prefix + sizeof size;
    cut(prefix + sizeof size + std::size_t{size} + sizeof(std::uint32_t));
    std::uint32_t crc = 0;
    std::memcpy(&crc, bytes.data() + body_at + size, sizeof crc);
    if (Crc32(bytes.substr(at, body_at + size - at)) != crc)
      throw core::UsageError(path + ": a corrupt sensing trace: " + name +
                             " fails its CRC-32; remove it to sense again");
    records.push_back({at, tag, bytes.substr(body_at, size)});
    at = body_at + size + sizeof crc;
  }
  if (bytes.size() - at != kDigestChars)
    throw core::UsageError(path +
                           ": a corrupt sensing trace: " + std::to_string(bytes.size() - at) +
                           " bytes after the end record where its 64-digit SHA-256 belongs; "
                           "remove it to sense again");
  return records;
}

// A frame record's body.
TracedFrame GetFrame(In& in, std::size_t nodes, const std::string& what, std::uint32_t* node) {
  *node = in.Get<std::uint32_t>();
  if (*node >= nodes) throw core::UsageError(what + " is of an unknown node");
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
  const auto further = in.Get<std::uint32_t>();
  // Each further observation takes at least 45 bytes (its flags, a point
  // observation without points: 40, an empty latent's count): a count the
  // record cannot hold is malformed, not an allocation.
  constexpr std::size_t kLeastFurtherBytes = 1 + 40 + 4;
  if (further > in.Left() / kLeastFurtherBytes) in.Malformed();
  f.content.further.resize(further);
  for (NodeObservation& o : f.content.further) {
    if (in.Get<std::uint8_t>() & kCamera)
      o.camera = GetCamera(in);
    else
      o.points = GetPoints(in);
    o.latent = in.Floats();
  }
  return f;
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
  std::string body;
  Out o(body);
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
  PutRecord(bytes_, std::string_view("\1", 1), body);
  ++frames_;
}

void SensingTraceWriter::Write(const std::string& dir) const {
  std::string header;
  Out h(header);
  h.Str(key_);
  h.Put(static_cast<std::uint32_t>(node_ids_.size()));
  for (const std::string& id : node_ids_) h.Str(id);
  std::string prefix(kMagic, sizeof kMagic);
  Out(prefix).Put(kSensingTraceVersion);
  std::string file;
  PutRecord(file, prefix, header);
  file += bytes_;
  std::string end;
  Out(end).Put(frames_);
  PutRecord(file, std::string_view("\0", 1), end);
  file += core::Sha256Hex(file);
  std::error_code ec;
  fs::create_directories(dir, ec);
  core::WriteFileAtomic(SensingTracePath(dir, key_), file);
}

TracedFrames ParseSensingTrace(const std::string& bytes, const std::string& path,
                               const std::string& key, const std::vector<std::string>& node_ids) {
  if (bytes.size() < sizeof kMagic || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw core::UsageError(path + ": not a uavsim sensing trace");
  if (bytes.size() < kHeaderPrefix)
    throw core::UsageError(path + ": a sensing trace cut short in the header (byte 0)");
  std::uint32_t version = 0;
  std::memcpy(&version, bytes.data() + sizeof kMagic, sizeof version);
  if (version != kSensingTraceVersion)
    throw core::UsageError(path + ": a sensing trace of format version " + std::to_string(version) +
                           "; this uavsim reads version " + std::to_string(kSensingTraceVersion) +
                           " (remove it to sense again)");
  const std::vector<Record> records = SplitRecords(bytes, path);
  const std::size_t digest_at = bytes.size() - kDigestChars;
  if (core::Sha256Hex(bytes.substr(0, digest_at)) != bytes.substr(digest_at))
    throw core::UsageError(path +
                           ": a corrupt sensing trace: its SHA-256 digest does not match its "
                           "bytes (every record's CRC-32 holds: the digest itself is damaged); "
                           "remove it to sense again");
  // Every byte checked: now read.
  const std::string header_name = path + ": the header of the sensing trace";
  In header(records.front().body, header_name);
  if (header.Str() != key)
    throw core::UsageError(path + ": a sensing trace of another sensing key");
  if (header.Get<std::uint32_t>() != node_ids.size() ||
      [&] {
        for (const std::string& id : node_ids)
          if (header.Str() != id) return true;
        return false;
      }() ||
      !header.AtEnd())
    throw core::UsageError(path + ": a sensing trace of other nodes");
  TracedFrames frames(node_ids.size());
  for (std::size_t i = 1; i + 1 < records.size(); ++i) {
    const std::string what = path + ": " + RecordName(i, records[i].at) + " of the sensing trace";
    In in(records[i].body, what);
    std::uint32_t node = 0;
    TracedFrame f = GetFrame(in, frames.size(), what, &node);
    if (!in.AtEnd()) in.Malformed();
    frames[node].push_back(std::move(f));
  }
  const std::string end_name = path + ": the end record of the sensing trace";
  In end(records.back().body, end_name);
  if (end.Get<std::uint64_t>() != records.size() - 2 || !end.AtEnd())
    throw core::UsageError(path + ": a sensing trace whose frame count does not match");
  return frames;
}

SensingTraceReader::SensingTraceReader(const std::string& dir, const std::string& key,
                                       const Scenario& s)
    : path_(SensingTracePath(dir, key)) {
  std::error_code ec;
  if (!fs::is_regular_file(path_, ec))
    throw core::UsageError(path_ + ": no sensing trace for this scenario's sensing (key " +
                           key.substr(0, 16) + "...); write one with --trace " + dir);
  frames_ = ParseSensingTrace(core::ReadFileBytes(path_), path_, key, NodeIds(s));
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
