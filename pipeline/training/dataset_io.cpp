#include "pipeline/training/dataset_io.h"

#include <unistd.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "core/error.h"

namespace uavsim::pipeline {
namespace {

// Version 02 adds each sample's fate and arrival time after on_time;
// version 01 files (without them) still read.
constexpr char kMagic[8] = {'U', 'A', 'V', 'E', 'P', 'S', '0', '2'};
constexpr char kMagicV01[8] = {'U', 'A', 'V', 'E', 'P', 'S', '0', '1'};
constexpr std::uint64_t kMaxCount = 1ull << 32;

class Writer {
 public:
  explicit Writer(std::ofstream& out) : out_(out) {}
  template <class T>
  void Pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out_.write(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void Vec3(const Eigen::Vector3d& v) { Pod(v.x()), Pod(v.y()), Pod(v.z()); }
  void String(const std::string& s) {
    Pod<std::uint64_t>(s.size());
    out_.write(s.data(), static_cast<std::streamsize>(s.size()));
  }
  void Floats(const std::vector<float>& v) {
    Pod<std::uint64_t>(v.size());
    out_.write(reinterpret_cast<const char*>(v.data()),
               static_cast<std::streamsize>(v.size() * sizeof(float)));
  }
  // Grey values k / 255 as the bytes k.
  void Grey(const std::vector<float>& v) {
    std::vector<std::uint8_t> b(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) b[i] = GreyByte(v[i]);
    Pod<std::uint64_t>(b.size());
    out_.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  }

 private:
  std::ofstream& out_;
};

class Reader {
 public:
  Reader(std::ifstream& in, std::string path, std::uint64_t size)
      : in_(in), path_(std::move(path)), size_(size) {}
  template <class T>
  T Pod() {
    T v{};
    Read(&v, sizeof v);
    return v;
  }
  // A count of items of at least `item_bytes` each: refused when the rest
  // of the file cannot hold them (before anything is allocated).
  std::uint64_t Count(std::uint64_t item_bytes) {
    const std::uint64_t at = Position();
    const auto n = Pod<std::uint64_t>();
    const auto left = size_ - Position();
    if (n > kMaxCount)
      Fail("corrupt at byte " + std::to_string(at) + " (a count of " + std::to_string(n) + ")");
    if (n * item_bytes > left) Truncated(at);
    return n;
  }
  Eigen::Vector3d Vec3() {
    const double x = Pod<double>(), y = Pod<double>(), z = Pod<double>();
    return {x, y, z};
  }
  std::string String() {
    std::string s(Count(1), '\0');
    Read(s.data(), s.size());
    return s;
  }
  std::vector<float> Floats() {
    std::vector<float> v(Count(4));
    Read(v.data(), v.size() * 4);
    return v;
  }
  std::vector<float> Grey() {
    std::vector<std::uint8_t> b(Count(1));
    Read(b.data(), b.size());
    return GreyFloats(b.data(), b.size());
  }
  // Bad input (exit 2), naming the file and where in it.
  [[noreturn]] void Fail(const std::string& what) const {
    throw core::ConfigError(path_, "", what);
  }
  // A record at byte `at` that runs past the file's end.
  [[noreturn]] void Truncated(std::uint64_t at) const {
    Fail("truncated at byte " + std::to_string(at) + " of " + std::to_string(size_) +
         " (an episode file cut short: written again, or copied whole?)");
  }
  std::uint64_t Position() const { return static_cast<std::uint64_t>(in_.tellg()); }

 private:
  void Read(void* to, std::size_t bytes) {
    const std::uint64_t at = Position();
    if (bytes > size_ - at) Truncated(at);
    in_.read(static_cast<char*>(to), static_cast<std::streamsize>(bytes));
    if (!in_) Truncated(at);
  }

  std::ifstream& in_;
  std::string path_;
  std::uint64_t size_;
};

}  // namespace

std::uint8_t GreyByte(float v) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
}

std::vector<float> GreyFloats(const std::uint8_t* bytes, std::size_t n) {
  if (n == 0) return {};
  // The same conversion as the camera pre-processor's (OpenCV's).
  cv::Mat f;
  cv::Mat(1, static_cast<int>(n), CV_8UC1, const_cast<std::uint8_t*>(bytes))
      .convertTo(f, CV_32F, 1.0 / 255.0);
  return std::vector<float>(f.ptr<float>(), f.ptr<float>() + f.total());
}

void WriteEpisodes(const std::vector<Episode>& episodes, const std::string& path) {
  for (const Episode& e : episodes)
    for (const Sample& s : e.samples)
      if ((s.modality == Modality::kCamera) != s.camera.has_value() ||
          (s.modality != Modality::kCamera) != s.points.has_value())
        throw std::invalid_argument(path + ": a " + ModalityName(s.modality) +
                                    " sample must carry exactly its own observation");
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    Writer w(out);
    out.write(kMagic, sizeof kMagic);
    w.Pod<std::uint64_t>(episodes.size());
    for (const Episode& e : episodes) {
      w.String(e.label);
      w.Pod(e.window_s);
      w.Pod<std::uint8_t>(e.raw_modalities);
      w.Pod<std::uint64_t>(e.window_truth.size());
      for (const auto& p : e.window_truth) w.Vec3(p);
      w.Pod<std::uint64_t>(e.samples.size());
      for (const Sample& s : e.samples) {
        w.Pod<std::uint8_t>(static_cast<std::uint8_t>(s.modality));
        w.Pod(s.node);
        w.Pod(s.t_s);
        w.Pod<std::uint8_t>(s.on_time);
        w.Pod<std::uint8_t>(static_cast<std::uint8_t>(s.fate));
        w.Pod(s.t_arrival_s);
        w.Vec3(s.truth_m);
        w.Pod<std::uint8_t>(s.camera ? 1 : 2);
        if (const auto& c = s.camera) {
          w.Pod(c->t_s);
          w.Pod<std::uint8_t>(c->detected);
          w.Grey(c->crop_left);
          w.Grey(c->crop_right);
          for (float f : {c->centre_left_px.x(), c->centre_left_px.y(), c->centre_right_px.x(),
                          c->centre_right_px.y(), c->side_left_px, c->side_right_px})
            w.Pod(f);
          for (const auto* v :
               {&c->eye_left_w, &c->eye_right_w, &c->bearing_left_w, &c->bearing_right_w})
            w.Vec3(*v);
        } else {
          const PointObservation& p = *s.points;
          w.Pod(p.t_s);
          w.Pod<std::int32_t>(p.channels);
          w.Floats(p.values);
          w.Vec3(p.sensor_position_w);
        }
      }
    }
    out.close();
    if (!out) {
      std::filesystem::remove(tmp);
      throw std::runtime_error(path + ": cannot write");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error(path + ": cannot write: " + ec.message());
}

const std::vector<Sample>& SampleList::View() const {
  static const std::vector<Sample> kNone;
  return p_ ? *p_ : kNone;
}

std::vector<Sample>& SampleList::Own() {
  if (!p_)
    p_ = std::make_shared<std::vector<Sample>>();
  else if (p_.use_count() > 1)
    p_ = std::make_shared<std::vector<Sample>>(*p_);
  return *p_;
}

const char* SampleFateName(SampleFate f) {
  switch (f) {
    case SampleFate::kOnTime:
      return "on_time";
    case SampleFate::kLate:
      return "late";
    case SampleFate::kLost:
      return "lost";
    case SampleFate::kInFlight:
      return "in_flight";
    case SampleFate::kUnknown:
      break;
  }
  return "unknown";
}

const char* DataSplitName(DataSplit s) { return s == DataSplit::kFrame ? "frame" : "trajectory"; }

std::string WeatherOf(const Episode& e) {
  const bool rain = e.label.find(", rain ") != std::string::npos;
  const bool fog = e.label.find(", fog ") != std::string::npos;
  return rain && fog ? "rain+fog" : rain ? "rain" : fog ? "fog" : "clear";
}

std::vector<Episode> ReadEpisodes(const std::string& path,
                                  const std::function<void()>& check_stop) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw std::runtime_error(path + ": cannot open: " + ec.message());
  Reader r(in, path, size);
  char magic[sizeof kMagic];
  in.read(magic, sizeof magic);
  const bool v01 = in && std::memcmp(magic, kMagicV01, sizeof kMagicV01) == 0;
  if (!in || (!v01 && std::memcmp(magic, kMagic, sizeof kMagic) != 0))
    r.Fail("not an episode file");
  std::vector<Episode> episodes(r.Count(8));
  for (Episode& e : episodes) {
    if (check_stop) check_stop();
    e.index = static_cast<int>(&e - episodes.data());
    e.label = r.String();
    e.window_s = r.Pod<double>();
    e.raw_modalities = v01 ? Episode::kRawUnknown : r.Pod<std::uint8_t>();
    if (e.raw_modalities > 7 && e.raw_modalities != Episode::kRawUnknown)
      r.Fail("corrupt (raw modalities " + std::to_string(e.raw_modalities) + ")");
    e.window_truth.resize(r.Count(24));
    for (auto& p : e.window_truth) p = r.Vec3();
    e.samples.resize(r.Count(v01 ? 50 : 59));
    for (Sample& s : e.samples) {
      const auto m = r.Pod<std::uint8_t>();
      if (m >= kModalityCount) r.Fail("corrupt (modality " + std::to_string(m) + ")");
      s.modality = static_cast<Modality>(m);
      s.node = r.Pod<std::uint32_t>();
      s.t_s = r.Pod<double>();
      s.on_time = r.Pod<std::uint8_t>() != 0;
      if (v01) {
        s.fate = s.on_time ? SampleFate::kOnTime : SampleFate::kUnknown;
        s.t_arrival_s = std::numeric_limits<double>::quiet_NaN();
      } else {
        const auto fate = r.Pod<std::uint8_t>();
        if (fate > static_cast<std::uint8_t>(SampleFate::kInFlight) &&
            fate != static_cast<std::uint8_t>(SampleFate::kUnknown))
          r.Fail("corrupt (fate " + std::to_string(fate) + ")");
        s.fate = static_cast<SampleFate>(fate);
        s.t_arrival_s = r.Pod<double>();
      }
      s.truth_m = r.Vec3();
      const auto kind = r.Pod<std::uint8_t>();
      if ((kind == 1) != (s.modality == Modality::kCamera))
        r.Fail("corrupt (a " + std::string(ModalityName(s.modality)) +
               " sample of the wrong kind)");
      if (kind == 1) {
        CameraObservation c;
        c.t_s = r.Pod<double>();
        c.detected = r.Pod<std::uint8_t>() != 0;
        c.crop_left = r.Grey();
        c.crop_right = r.Grey();
        float g[6];
        for (float& f : g) f = r.Pod<float>();
        c.centre_left_px = {g[0], g[1]};
        c.centre_right_px = {g[2], g[3]};
        c.side_left_px = g[4];
        c.side_right_px = g[5];
        for (auto* v : {&c.eye_left_w, &c.eye_right_w, &c.bearing_left_w, &c.bearing_right_w})
          *v = r.Vec3();
        s.camera = std::move(c);
      } else if (kind == 2) {
        PointObservation p;
        p.t_s = r.Pod<double>();
        p.channels = r.Pod<std::int32_t>();
        p.values = r.Floats();
        p.sensor_position_w = r.Vec3();
        s.points = std::move(p);
      } else {
        r.Fail("corrupt (sample kind " + std::to_string(kind) + ")");
      }
    }
  }
  return episodes;
}

}  // namespace uavsim::pipeline
