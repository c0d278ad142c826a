// The training-episode file (pipeline/training/dataset_io.h): every field survives a
// round trip, camera crops as 8-bit greys, and a truncated, foreign or
// missing file is refused with its path named.
#include <catch2/catch.hpp>
#include <filesystem>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>
#include <vector>

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
  a.samples.push_back(CameraSample(0.0331, 0, true, 0, 128));
  a.samples.push_back(PointSample(Modality::kLidar, 0.05, 1, true, 6));
  a.samples.push_back(PointSample(Modality::kRadar, 0.0667, 2, false, 3));
  a.samples.push_back(CameraSample(0.0664, 0, false, 17, 128));
  a.samples.push_back(PointSample(Modality::kRadar, 0.1333, 4294967295u, true, 1));
  a.samples.push_back(PointSample(Modality::kLidar, 0.15, 3, false, 0));  // empty cloud
  Sample undetected = CameraSample(0.1, 5, true, 0, 0);                   // no crops at all
  undetected.camera->detected = false;
  a.samples.push_back(undetected);
  for (int k = 1; k <= 4; ++k) a.window_truth.push_back({0.1 * k, -0.2 * k, 30.0 + k / 7.0});

  Episode& b = episodes[1];  // nothing at all
  b.label = "";
  b.window_s = 0.125;

  Episode& c = episodes[2];
  c.label = "line seed 3 \xc3\xa9t\xc3\xa9";
  c.window_s = 0.5;
  c.samples.push_back(PointSample(Modality::kRadar, 1.0, 9, true, 2));
  c.window_truth.push_back({1.0, 2.0, 3.0});
  return episodes;
}

void CheckSameSample(const Sample& a, const Sample& b) {
  CHECK(a.modality == b.modality);
  CHECK(a.node == b.node);
  CHECK(a.t_s == b.t_s);
  CHECK(a.on_time == b.on_time);
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
  for (std::size_t n = bytes.size(); n-- > 0;) {
    fs::resize_file(cut, n);
    INFO("first " << n << " of " << bytes.size() << " bytes");
    CHECK_THAT(RuntimeErrorOf([&] { ReadEpisodes(cut); }), Catch::Contains(cut));
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
