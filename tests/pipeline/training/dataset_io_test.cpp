// The training-episode file (pipeline/training/dataset_io.h): every field survives a
// round trip (the fates and arrival times of version 02 too), camera crops as
// 8-bit greys, a version 01 file still reads, and a truncated, foreign or
// missing file is refused with its path named.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.h"
#include "pipeline/training/dataset.h"
#include "pipeline/training/dataset_io.h"
#include "test_support.h"

namespace uavsim::pipeline {
namespace {

// The 8-bit grey k as the camera pre-processor makes it a float (OpenCV's
// convertTo with scale 1/255: not always the same float as k / 255.0f).
float Grey(int k) {
  const std::uint8_t b = static_cast<std::uint8_t>(k);
  cv::Mat f;
  cv::Mat(1, 1, CV_8UC1, const_cast<std::uint8_t*>(&b)).convertTo(f, CV_32F, 1.0 / 255.0);
  return f.at<float>(0, 0);
}

namespace fs = std::filesystem;

// A camera sample whose crops hold grey values k / 255 (every k appears).
Sample CameraSample(double t, std::uint32_t node, bool on_time, int shift, int crop_px) {
  Sample s;
  s.modality = Modality::kCamera;
  s.node = node;
  s.t_s = t;
  s.on_time = on_time;
  s.truth_m = {1.25 + t, -3.1 * t, 30.0 + 0.001 * t};
  CameraObservation c;
  c.t_s = t - 1e-4;
  c.detected = true;
  const auto n = static_cast<std::size_t>(crop_px) * static_cast<std::size_t>(crop_px);
  c.crop_left.resize(n);
  c.crop_right.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    c.crop_left[i] = Grey(static_cast<int>((i + static_cast<std::size_t>(shift)) % 256));
    c.crop_right[i] = Grey(static_cast<int>((i * 7 + 3) % 256));
  }
  c.centre_left_px = {321.5f, 199.25f};
  c.centre_right_px = {300.125f, 200.75f};
  c.side_left_px = 41.0f;
  c.side_right_px = 39.5f;
  c.eye_left_w = {-30.06, -30.0, 1.5};
  c.eye_right_w = {-29.94, -30.0, 1.5};
  c.bearing_left_w = Eigen::Vector3d(1.0, 0.9, 0.7).normalized();
  c.bearing_right_w = Eigen::Vector3d(1.0, 0.91, 0.7).normalized();
  s.camera = std::move(c);
  return s;
}

Sample PointSample(Modality m, double t, std::uint32_t node, bool on_time, int points) {
  Sample s;
  s.modality = m;
  s.node = node;
  s.t_s = t;
  s.on_time = on_time;
  s.truth_m = {-7.0 + t, 0.3, 25.0 - t / 3.0};
  PointObservation p;
  p.t_s = t;
  p.channels = m == Modality::kLidar ? 4 : 5;
  for (int i = 0; i < points * p.channels; ++i)
    p.values.push_back(0.1f * static_cast<float>(i) - 1.0f / 3.0f);
  p.sensor_position_w =
      m == Modality::kLidar ? Eigen::Vector3d(20.0, -20.0, 1.0) : Eigen::Vector3d(-24.0, 24.0, 1.5);
  s.points = std::move(p);
  return s;
}

std::vector<Episode> SomeEpisodes() {
  std::vector<Episode> episodes(3);
  Episode& a = episodes[0];
  a.label = "orbit seed 7 rain 4 mm/h loss 0.12";
  a.window_s = 0.2;
  a.raw_modalities = 5;  // camera and radar sent raw data
  a.samples.push_back(CameraSample(0.0331, 0, true, 0, 128));
  a.samples.push_back(PointSample(Modality::kLidar, 0.05, 1, true, 6));
  a.samples.push_back(PointSample(Modality::kRadar, 0.0667, 2, false, 3));
  a.samples.push_back(CameraSample(0.0664, 0, false, 17, 128));
  a.samples.push_back(PointSample(Modality::kRadar, 0.1333, 4294967295u, true, 1));
  a.samples.push_back(PointSample(Modality::kLidar, 0.15, 3, false, 0));  // empty cloud
  Sample undetected = CameraSample(0.1, 5, true, 0, 0);                   // no crops at all
  undetected.camera->detected = false;
  a.samples.push_back(undetected);
  // Every fate, with arrival times where they arrived.
  const SampleFate fates[] = {SampleFate::kOnTime, SampleFate::kOnTime, SampleFate::kLate,
                              SampleFate::kLost,   SampleFate::kOnTime, SampleFate::kInFlight,
                              SampleFate::kOnTime};
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    Sample& s = a.samples[i];
    s.fate = fates[i];
    if (s.fate == SampleFate::kOnTime || s.fate == SampleFate::kLate)
      s.t_arrival_s = s.t_s + 0.0123 * static_cast<double>(i + 1);
  }
  for (int k = 1; k <= 4; ++k) a.window_truth.push_back({0.1 * k, -0.2 * k, 30.0 + k / 7.0});

  Episode& b = episodes[1];  // nothing at all
  b.label = "";
  b.window_s = 0.125;

  Episode& c = episodes[2];
  c.label = "line seed 3 \xc3\xa9t\xc3\xa9";
  c.window_s = 0.5;
  c.samples.push_back(PointSample(Modality::kRadar, 1.0, 9, true, 2));
  c.samples[0].fate = SampleFate::kUnknown;  // as read from a version 01 file
  c.window_truth.push_back({1.0, 2.0, 3.0});
  return episodes;
}

void CheckSameSample(const Sample& a, const Sample& b) {
  CHECK(a.modality == b.modality);
  CHECK(a.node == b.node);
  CHECK(a.t_s == b.t_s);
  CHECK(a.on_time == b.on_time);
  CHECK(a.fate == b.fate);
  // The same double, NaN included.
  CHECK(std::memcmp(&a.t_arrival_s, &b.t_arrival_s, sizeof(double)) == 0);
  CHECK(a.truth_m == b.truth_m);
  REQUIRE(a.camera.has_value() == b.camera.has_value());
  REQUIRE(a.points.has_value() == b.points.has_value());
  if (a.camera) {
    const CameraObservation &x = *a.camera, &y = *b.camera;
    CHECK(x.t_s == y.t_s);
    CHECK(x.detected == y.detected);
    CHECK(x.crop_left == y.crop_left);
    CHECK(x.crop_right == y.crop_right);
    CHECK(x.centre_left_px == y.centre_left_px);
    CHECK(x.centre_right_px == y.centre_right_px);
    CHECK(x.side_left_px == y.side_left_px);
    CHECK(x.side_right_px == y.side_right_px);
    CHECK(x.eye_left_w == y.eye_left_w);
    CHECK(x.eye_right_w == y.eye_right_w);
    CHECK(x.bearing_left_w == y.bearing_left_w);
    CHECK(x.bearing_right_w == y.bearing_right_w);
  }
  if (a.points) {
    CHECK(a.points->t_s == b.points->t_s);
    CHECK(a.points->channels == b.points->channels);
    CHECK(a.points->values == b.points->values);
    CHECK(a.points->sensor_position_w == b.points->sensor_position_w);
  }
}

// The what() of the std::runtime_error `f` throws, or "" if none.
template <class F>
std::string RuntimeErrorOf(F&& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("DatasetIo: every field survives a round trip", "[pipeline]") {
  const std::string dir = testing::TempDir("dataset-io");
  const std::string path = dir + "/episodes.bin";
  const std::vector<Episode> written = SomeEpisodes();
  WriteEpisodes(written, path);
  const std::vector<Episode> read = ReadEpisodes(path);
  REQUIRE(read.size() == written.size());
  for (std::size_t e = 0; e < read.size(); ++e) {
    INFO("episode " << e);
    CHECK(read[e].label == written[e].label);
    CHECK(read[e].window_s == written[e].window_s);
    CHECK(read[e].raw_modalities == written[e].raw_modalities);
    CHECK(read[e].window_truth == written[e].window_truth);
    REQUIRE(read[e].samples.size() == written[e].samples.size());
    for (std::size_t i = 0; i < read[e].samples.size(); ++i) {
      INFO("sample " << i);
      CheckSameSample(read[e].samples[i], written[e].samples[i]);
    }
  }
  // The crops really hold 128 x 128 values each (nothing dropped or padded).
  REQUIRE(read[0].samples[0].camera.has_value());
  CHECK(read[0].samples[0].camera->crop_left.size() == 128u * 128u);
  CHECK(read[0].samples[6].camera->crop_left.empty());

  // Written atomically: nothing but the file itself in the folder.
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    ++files;
    CHECK(entry.path().filename() == "episodes.bin");
  }
  CHECK(files == 1);

  // Rewriting the same episodes gives the same bytes.
  const std::string again = dir + "/again.bin";
  WriteEpisodes(read, again);
  CHECK(testing::ReadFile(again) == testing::ReadFile(path));

  // No episodes at all is a valid file too.
  WriteEpisodes({}, dir + "/none.bin");
  CHECK(ReadEpisodes(dir + "/none.bin").empty());
}

// Bytes of a little-endian file, appended field by field (this machine is
// little-endian, as the episode file is).
struct Bytes {
  std::string b;
  template <class T>
  Bytes& Pod(T v) {
    b.append(reinterpret_cast<const char*>(&v), sizeof v);
    return *this;
  }
  Bytes& Vec3(double x, double y, double z) { return Pod(x).Pod(y).Pod(z); }
};

TEST_CASE("DatasetIo: a version 01 file (no fates, no arrival times) still reads", "[pipeline]") {
  // The version 01 layout, written by hand as the old writer wrote it: one
  // episode with a camera sample on time and a radar sample that was not.
  Bytes f;
  f.b = "UAVEPS01";
  f.Pod<std::uint64_t>(1);
  const std::string label = "orbit r 40 m, loss 12 %";
  f.Pod<std::uint64_t>(label.size());
  f.b += label;
  f.Pod(0.2);
  f.Pod<std::uint64_t>(2).Vec3(1, 2, 3).Vec3(4, 5, 6);  // window truths
  f.Pod<std::uint64_t>(2);                              // samples
  // The camera sample: 2 x 2 crops of greys 0, 64, 128, 255 and 1, 2, 3, 4.
  f.Pod<std::uint8_t>(0).Pod<std::uint32_t>(3).Pod(0.0331).Pod<std::uint8_t>(1);
  f.Vec3(10, 20, 30).Pod<std::uint8_t>(1);
  f.Pod(0.033).Pod<std::uint8_t>(1);
  f.Pod<std::uint64_t>(4);
  f.b += std::string("\x00\x40\x80\xff", 4);
  f.Pod<std::uint64_t>(4);
  f.b += std::string("\x01\x02\x03\x04", 4);
  for (float g : {321.5f, 199.25f, 300.125f, 200.75f, 41.0f, 39.5f}) f.Pod(g);
  f.Vec3(-1, 0, 1).Vec3(1, 0, 1).Vec3(0, 1, 0).Vec3(0, 0, 1);
  // The radar sample: 2 points of 5 channels.
  f.Pod<std::uint8_t>(2).Pod<std::uint32_t>(7).Pod(0.0667).Pod<std::uint8_t>(0);
  f.Vec3(11, 21, 31).Pod<std::uint8_t>(2);
  f.Pod(0.0666).Pod<std::int32_t>(5).Pod<std::uint64_t>(10);
  for (int i = 0; i < 10; ++i) f.Pod(0.5f * static_cast<float>(i));
  f.Vec3(-24, 24, 1.5);

  const std::string path = testing::TempDir("dataset-io-v01") + "/v01.bin";
  testing::WriteFile(path, f.b);
  const std::vector<Episode> read = ReadEpisodes(path);
  REQUIRE(read.size() == 1);
  const Episode& e = read[0];
  CHECK(e.label == label);
  CHECK(e.window_s == 0.2);
  CHECK(e.raw_modalities == Episode::kRawUnknown);  // v01 did not record it
  CHECK(e.window_truth ==
        std::vector<Eigen::Vector3d>{Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(4, 5, 6)});
  REQUIRE(e.samples.size() == 2);
  const Sample& cam = e.samples[0];
  CHECK(cam.modality == Modality::kCamera);
  CHECK(cam.node == 3);
  CHECK(cam.t_s == 0.0331);
  CHECK(cam.on_time);
  CHECK(cam.fate == SampleFate::kOnTime);  // on time: the one fate v01 knew
  CHECK(std::isnan(cam.t_arrival_s));      // but not when
  CHECK(cam.truth_m == Eigen::Vector3d(10, 20, 30));
  REQUIRE(cam.camera.has_value());
  CHECK(cam.camera->t_s == 0.033);
  CHECK(cam.camera->detected);
  CHECK(cam.camera->crop_left == std::vector<float>{Grey(0), Grey(64), Grey(128), Grey(255)});
  CHECK(cam.camera->crop_right == std::vector<float>{Grey(1), Grey(2), Grey(3), Grey(4)});
  CHECK(cam.camera->centre_right_px == Eigen::Vector2f(300.125f, 200.75f));
  CHECK(cam.camera->side_right_px == 39.5f);
  CHECK(cam.camera->bearing_right_w == Eigen::Vector3d(0, 0, 1));
  const Sample& radar = e.samples[1];
  CHECK(radar.modality == Modality::kRadar);
  CHECK(radar.node == 7);
  CHECK_FALSE(radar.on_time);
  CHECK(radar.fate == SampleFate::kUnknown);  // late, lost or in flight: v01 did not say
  CHECK(std::string(SampleFateName(radar.fate)) == "unknown");
  CHECK(std::isnan(radar.t_arrival_s));
  REQUIRE(radar.points.has_value());
  CHECK(radar.points->channels == 5);
  CHECK(radar.points->values.size() == 10);
  CHECK(radar.points->values[9] == 4.5f);
  CHECK(radar.points->sensor_position_w == Eigen::Vector3d(-24, 24, 1.5));

  // Rewritten, it is a version 02 file that reads back the same.
  const std::string v02 = testing::TempDir("dataset-io-v01") + "/v02.bin";
  WriteEpisodes(read, v02);
  CHECK(testing::ReadFile(v02).substr(0, 8) == "UAVEPS02");
  const std::vector<Episode> again = ReadEpisodes(v02);
  REQUIRE(again.size() == 1);
  REQUIRE(again[0].samples.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) CheckSameSample(again[0].samples[i], e.samples[i]);
}

TEST_CASE("DatasetIo: a sample's fate outside the known values is refused", "[pipeline]") {
  const std::string dir = testing::TempDir("dataset-io-fate");
  const std::string path = dir + "/episodes.bin";
  std::vector<Episode> episodes(1);
  episodes[0].samples.push_back(PointSample(Modality::kLidar, 0.05, 1, false, 1));
  episodes[0].samples[0].fate = SampleFate::kLost;
  WriteEpisodes(episodes, path);
  std::string bytes = testing::ReadFile(path);
  // magic, count, label size (empty label), window_s, raw modalities, K = 0,
  // N, then the sample: modality, node, t_s, on_time, fate.
  const std::size_t at = 8 + 8 + 8 + 8 + 1 + 8 + 8 + 1 + 4 + 8 + 1;
  REQUIRE(static_cast<std::uint8_t>(bytes[at]) == 2);
  bytes[at] = 4;
  const std::string bad = dir + "/bad-fate.bin";
  testing::WriteFile(bad, bytes);
  const std::string what = RuntimeErrorOf([&] { ReadEpisodes(bad); });
  CHECK_THAT(what, Catch::Contains(bad));
  CHECK_THAT(what, Catch::Contains("fate 4"));
  // The same for an episode's raw modalities (bits 0-2, or 255 unknown).
  std::string raw = testing::ReadFile(path);
  REQUIRE(raw[8 + 8 + 8 + 8] == 0);
  raw[8 + 8 + 8 + 8] = 9;
  testing::WriteFile(bad, raw);
  CHECK_THAT(RuntimeErrorOf([&] { ReadEpisodes(bad); }), Catch::Contains("raw modalities 9"));
}

TEST_CASE("DatasetIo: crops are stored as the nearest 8-bit grey", "[pipeline]") {
  const std::string path = testing::TempDir("dataset-io-grey") + "/episodes.bin";
  std::vector<Episode> episodes(1);
  episodes[0].samples.push_back(CameraSample(0.01, 0, true, 0, 2));
  episodes[0].samples[0].camera->crop_left = {0.502f, -0.25f, 1.75f, 0.098f};
  WriteEpisodes(episodes, path);
  const std::vector<float> left = ReadEpisodes(path).at(0).samples.at(0).camera->crop_left;
  CHECK(left == std::vector<float>{Grey(128), Grey(0), Grey(255), Grey(25)});
}

TEST_CASE("DatasetIo: a truncated file is refused with its path named", "[pipeline]") {
  const std::string dir = testing::TempDir("dataset-io-truncated");
  const std::string path = dir + "/episodes.bin";
  std::vector<Episode> episodes = SomeEpisodes();
  // Small crops so that every prefix of the file can be tried.
  episodes[0].samples[0] = CameraSample(0.0331, 0, true, 0, 3);
  episodes[0].samples[3] = CameraSample(0.0664, 0, false, 5, 2);
  WriteEpisodes(episodes, path);
  const std::string bytes = testing::ReadFile(path);
  REQUIRE(bytes.size() > 100);
  REQUIRE(bytes.size() < 4000);
  // Every prefix, cut in place from the longest down.
  const std::string cut = dir + "/cut.bin";
  testing::WriteFile(cut, bytes);
  CHECK(ReadEpisodes(cut).size() == 3);  // the whole file still reads
  // Bad input (exit 2) that says where the file ends (issue 43: exit 1 and
  // "corrupt (a count of 16384)").
  const auto bad_input_of = [&] {
    try {
      ReadEpisodes(cut);
    } catch (const core::ConfigError& e) {
      return std::string(e.what());
    } catch (const std::exception& e) {
      return std::string("not a ConfigError: ") + e.what();
    }
    return std::string();
  };
  for (std::size_t n = bytes.size(); n-- > 0;) {
    fs::resize_file(cut, n);
    INFO("first " << n << " of " << bytes.size() << " bytes");
    const std::string what = bad_input_of();
    if (n < 8) {
      CHECK(what == cut + ": not an episode file");
      continue;
    }
    CHECK_THAT(what, Catch::StartsWith(cut + ": truncated at byte "));
    CHECK_THAT(what, Catch::Contains(" of " + std::to_string(n) + " ("));
  }
}

TEST_CASE("DatasetIo: a foreign or missing file is refused with its path named", "[pipeline]") {
  const std::string dir = testing::TempDir("dataset-io-foreign");
  const std::string path = dir + "/episodes.bin";
  WriteEpisodes(SomeEpisodes(), path);
  std::string bytes = testing::ReadFile(path);

  const std::string wrong_magic = dir + "/wrong-magic.bin";
  bytes[0] = 'X';
  testing::WriteFile(wrong_magic, bytes);
  const std::string what = RuntimeErrorOf([&] { ReadEpisodes(wrong_magic); });
  CHECK_THAT(what, Catch::Contains(wrong_magic));
  CHECK_THAT(what, Catch::Contains("not an episode file"));

  const std::string other_version = dir + "/other-version.bin";
  bytes[0] = 'U';
  bytes[7] = '9';  // "UAVEPS09"
  testing::WriteFile(other_version, bytes);
  CHECK_THAT(RuntimeErrorOf([&] { ReadEpisodes(other_version); }), Catch::Contains(other_version));

  const std::string text = dir + "/text.json";
  testing::WriteFile(text, "{\"episodes\": []}\n");
  CHECK_THAT(RuntimeErrorOf([&] { ReadEpisodes(text); }), Catch::Contains(text));

  const std::string missing = dir + "/missing.bin";
  CHECK_THAT(RuntimeErrorOf([&] { ReadEpisodes(missing); }), Catch::Contains(missing));

  const std::string unwritable = dir + "/no-such-folder/episodes.bin";
  CHECK_THAT(RuntimeErrorOf([&] { WriteEpisodes(SomeEpisodes(), unwritable); }),
             Catch::Contains(unwritable));
}

}  // namespace uavsim::pipeline
