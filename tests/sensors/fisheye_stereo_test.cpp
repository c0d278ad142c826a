// FisheyeStereo in small hand-built worlds, checked against independent
// references: OpenCV's cv::omnidir::projectPoints for where things appear,
// Koschmieder's law for fog, and image statistics for noise and night.
#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/ccalib/omnidir.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <vector>

#include "core/error.h"
#include "core/json_io.h"
#include "core/world_geometry.h"
#include "sensors/fisheye_stereo.h"
#include "sensors/image_io.h"

namespace uavsim::sensors {
namespace {

using Eigen::Vector3d;
using Eigen::Vector3f;

constexpr double kPi = 3.14159265358979323846;

core::TriangleMesh Box(const Vector3d& center_m, double side_m, std::uint32_t material) {
  core::TriangleMesh m;
  m.name = "box";
  m.material = material;
  const float h = static_cast<float>(side_m / 2);
  for (int i = 0; i < 8; ++i)
    m.vertices_m.push_back(center_m.cast<float>() +
                           Vector3f(i & 1 ? h : -h, i & 2 ? h : -h, i & 4 ? h : -h));
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

// A rectangle through `center_m` spanned by the half-axes a and b.
core::TriangleMesh Quad(const Vector3d& center_m, const Vector3d& a, const Vector3d& b,
                        std::uint32_t material) {
  core::TriangleMesh m;
  m.name = "quad";
  m.material = material;
  for (const Vector3d& p : std::vector<Vector3d>{center_m - a - b, center_m + a - b,
                                                 center_m + a + b, center_m - a + b})
    m.vertices_m.push_back(p.cast<float>());
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

core::TriangleMesh Ground() {
  return Quad(Vector3d::Zero(), Vector3d(100, 0, 0), Vector3d(0, 100, 0), core::kMaterialGround);
}

// The camera-from-world transform written out from the conventions
// (REP 103 body, optical frame x_C = -y_B, y_C = -z_B, z_C = x_B, right eye
// baseline along +x_C), independently of FisheyeStereo.
Eigen::Isometry3d X_CW(const FisheyeStereoConfig& c, bool right_eye) {
  Eigen::Matrix3d R_CB;
  R_CB << 0, -1, 0,  //
      0, 0, -1,      //
      1, 0, 0;
  const Eigen::Isometry3d X_WB = c.pose.ToIsometry();
  Eigen::Isometry3d X_CB = Eigen::Isometry3d::Identity();
  X_CB.linear() = R_CB;
  Eigen::Isometry3d X = X_CB * X_WB.inverse();
  if (right_eye) X.translation() -= Vector3d(c.baseline_m, 0, 0);
  return X;
}

// Where cv::omnidir::projectPoints puts the world point p_W.
Eigen::Vector2d OpenCvPixel(const FisheyeStereoConfig& c, bool right_eye, const Vector3d& p_W) {
  const Eigen::Isometry3d X = X_CW(c, right_eye);
  cv::Matx33d R;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) R(r, k) = X.linear()(r, k);
  cv::Vec3d rvec;
  cv::Rodrigues(R, rvec);
  const cv::Vec3d tvec(X.translation().x(), X.translation().y(), X.translation().z());
  const cv::Matx33d K(c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1);
  const cv::Vec4d D(c.k1, c.k2, c.p1, c.p2);
  std::vector<cv::Vec3d> object{{p_W.x(), p_W.y(), p_W.z()}};
  std::vector<cv::Vec2d> image;
  cv::omnidir::projectPoints(object, image, rvec, tvec, cv::Mat(K), c.xi, cv::Mat(D));
  return {image[0][0], image[0][1]};
}

FisheyeStereoConfig TestCamera() {
  FisheyeStereoConfig c;
  c.pose.position_m = {0, 0, 1.5};
  c.pose.rpy_deg = {0, -20, 30};  // looking 20 degrees up, 30 degrees left of east
  c.xi = 0.9;
  c.fx_px = 240;
  c.fy_px = 235;
  c.cx_px = 322.5;
  c.cy_px = 238.0;
  c.k1 = -0.1;
  c.k2 = 0.02;
  c.p1 = 5e-4;
  c.p2 = -3e-4;
  c.sensor_noise = false;
  return c;
}

double Linear(std::uint8_t dn, double gamma) { return std::pow(dn / 255.0, gamma); }

// Centroid of the pixels where `with` differs from `without` (the same
// world without the object), weighted by the linear radiance difference,
// which is proportional to the object's coverage of each pixel.
Eigen::Vector2d DifferenceCentroid(const GrayImage& with, const GrayImage& without, double gamma,
                                   double* peak_dn = nullptr) {
  double sum = 0, su = 0, sv = 0, peak = 0;
  for (int v = 0; v < with.height; ++v) {
    for (int u = 0; u < with.width; ++u) {
      const double d = std::abs(Linear(with.at(u, v), gamma) - Linear(without.at(u, v), gamma));
      peak = std::max(peak, std::abs(double(with.at(u, v)) - without.at(u, v)));
      sum += d;
      su += d * u;
      sv += d * v;
    }
  }
  if (peak_dn) *peak_dn = peak;
  REQUIRE(sum > 0);
  return {su / sum, sv / sum};
}

// Centroid of the pixels that differ by more than threshold_dn.
Eigen::Vector2d BlobCentroid(const GrayImage& with, const GrayImage& without, int threshold_dn,
                             int* count_out) {
  double su = 0, sv = 0;
  int count = 0;
  for (int v = 0; v < with.height; ++v)
    for (int u = 0; u < with.width; ++u)
      if (std::abs(int(with.at(u, v)) - int(without.at(u, v))) > threshold_dn) {
        su += u;
        sv += v;
        ++count;
      }
  *count_out = count;
  REQUIRE(count > 0);
  return {su / count, sv / count};
}

StereoFrame Render(const FisheyeStereoConfig& c, const core::WorldGeometry& world,
                   const core::WeatherConfig& weather, std::uint64_t seed,
                   const std::vector<BoundingSphere>& small = {}) {
  RaycastScene scene(world);
  FisheyeStereo camera(c, scene);
  if (!small.empty()) camera.set_small_objects([small](double) { return small; });
  core::RngStream noise(seed, "camera");
  return camera.Capture(0.0, weather, noise);
}

double Mean(const GrayImage& image) {
  double s = 0;
  for (std::uint8_t p : image.pixels) s += p;
  return s / image.pixels.size();
}

TEST_CASE("FisheyeStereo: a box appears where cv::omnidir::projectPoints puts it", "[sensors]") {
  const FisheyeStereoConfig c = TestCamera();
  // 15 m away, 30 degrees right of the optical axis and 15 degrees above it.
  const double az = 60 * kPi / 180, el = 35 * kPi / 180;
  const Vector3d center =
      Vector3d(0, 0, 1.5) +
      15.0 * Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  core::WorldGeometry empty;
  empty.meshes = {Ground()};
  core::WorldGeometry with_box = empty;
  with_box.meshes.push_back(Box(center, 0.4, core::kMaterialDrone));
  const StereoFrame a = Render(c, with_box, {}, 1);
  const StereoFrame b = Render(c, empty, {}, 1);

  for (bool right : {false, true}) {
    INFO((right ? "right" : "left") << " eye");
    const Eigen::Vector2d expected = OpenCvPixel(c, right, center);
    int count = 0;
    const Eigen::Vector2d got =
        BlobCentroid(right ? a.right : a.left, right ? b.right : b.left, 8, &count);
    INFO("blob of " << count << " px at " << got.transpose() << ", OpenCV "
                    << expected.transpose());
    CHECK(count >= 10);  // a 0.4 m box at 15 m spans about 6 px
    CHECK((got - expected).norm() < 1.0);
  }
  // The drone-dark box stands out against the bright sky.
  const Eigen::Vector2d p = OpenCvPixel(c, false, center);
  const int u = static_cast<int>(std::lround(p.x())), v = static_cast<int>(std::lround(p.y()));
  CHECK(int(b.left.at(u, v)) - int(a.left.at(u, v)) > 100);
}

TEST_CASE("FisheyeStereo: a sub-pixel UAV far away is integrated over its pixels", "[sensors]") {
  const FisheyeStereoConfig c = TestCamera();
  const double az = 40 * kPi / 180, el = 25 * kPi / 180;
  const Vector3d center =
      Vector3d(0, 0, 1.5) +
      70.0 * Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  // 0.4 m at 70 m: under a pixel across, easily lost between pixel centres.
  core::WorldGeometry empty;
  empty.meshes = {Ground()};
  core::WorldGeometry with_box = empty;
  with_box.meshes.push_back(Box(center, 0.4, core::kMaterialDrone));
  const std::vector<BoundingSphere> small{{center, 0.4 * std::sqrt(3.0) / 2}};
  const StereoFrame a = Render(c, with_box, {}, 1, small);
  const StereoFrame b = Render(c, empty, {}, 1, small);
  for (bool right : {false, true}) {
    INFO((right ? "right" : "left") << " eye");
    double peak_dn = 0;
    const Eigen::Vector2d got =
        DifferenceCentroid(right ? a.right : a.left, right ? b.right : b.left, c.gamma, &peak_dn);
    const Eigen::Vector2d expected = OpenCvPixel(c, right, center);
    INFO("centroid " << got.transpose() << ", OpenCV " << expected.transpose() << ", peak "
                     << peak_dn << " DN");
    CHECK(peak_dn >= 8);
    CHECK((got - expected).norm() < 0.5);
  }
}

TEST_CASE("FisheyeStereo: the optical frame follows REP 103 and the right eye sits right",
          "[sensors]") {
  FisheyeStereoConfig c;  // default lens: cx 320, cy 240
  c.pose.position_m = {0, 0, 10};
  c.sensor_noise = false;
  core::WorldGeometry world;
  world.meshes = {Box({20, 0, 10}, 2.0, core::kMaterialDrone),   // ahead (body +x)
                  Box({20, 8, 10}, 2.0, core::kMaterialDrone),   // left (body +y)
                  Box({20, 0, 18}, 2.0, core::kMaterialDrone)};  // above (body +z)
  RaycastScene scene(world);
  const FisheyeStereo camera(c, scene);
  const Eigen::Isometry3d& left = camera.X_WC(FisheyeStereo::Eye::kLeft);
  const Eigen::Isometry3d& right = camera.X_WC(FisheyeStereo::Eye::kRight);
  CHECK((left.linear() * Vector3d::UnitZ() - Vector3d::UnitX()).norm() < 1e-12);
  CHECK((left.linear() * Vector3d::UnitX() + Vector3d::UnitY()).norm() < 1e-12);
  CHECK((left.linear() * Vector3d::UnitY() + Vector3d::UnitZ()).norm() < 1e-12);
  CHECK((right.translation() - left.translation() - Vector3d(0, -c.baseline_m, 0)).norm() < 1e-12);
  core::RngStream noise(1, "camera");
  const StereoFrame f = camera.Capture(0.0, {}, noise);
  // With xi = 1 a ray theta off the axis lands fx tan(theta / 2) from the
  // principal point: the side boxes (theta = atan(8 / 20)) 44 px away.
  CHECK(int(f.left.at(320, 240)) < 100);       // the box ahead: dark at the principal point
  CHECK(int(f.left.at(320 - 44, 240)) < 100);  // body left is image left
  CHECK(int(f.left.at(320, 240 - 44)) < 100);  // body up is image up
  CHECK(int(f.left.at(320 + 44, 240)) > 150);  // nothing to the right: sky
  CHECK(int(f.left.at(320, 240 + 44)) > 150);  // nor below
}

TEST_CASE("FisheyeStereo: fog fades a far wall toward the airlight as Koschmieder predicts",
          "[sensors]") {
  FisheyeStereoConfig c;
  c.pose.position_m = {0, 0, 1.5};
  c.sensor_noise = false;
  const double distance_m = 80.0;
  core::WorldGeometry world;  // a wall ahead, nothing else: the rest of the view is sky
  world.meshes = {
      Quad({distance_m, 0, 1.5}, Vector3d(0, 20, 0), Vector3d(0, 0, 12), core::kMaterialConcrete)};
  auto linear_patch = [&](const GrayImage& im, int u0, int v0) {
    double s = 0;
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) s += Linear(im.at(u0 + du, v0 + dv), c.gamma);
    return s / 9;
  };
  const GrayImage clear = Render(c, world, {}, 1).left;
  const double wall_clear = linear_patch(clear, 320, 240);
  for (double visibility_m : {150.0, 300.0, 600.0}) {
    INFO("visibility " << visibility_m << " m");
    core::WeatherConfig fog;
    fog.fog_visibility_m = visibility_m;
    const GrayImage foggy = Render(c, world, fog, 1).left;
    const double wall = linear_patch(foggy, 320, 240);
    const double airlight = linear_patch(foggy, 320, 10);  // straight up: a miss
    const double expected = std::exp(-3.912 / visibility_m * distance_m);
    const double measured = (airlight - wall) / (airlight - wall_clear);
    INFO("contrast ratio " << measured << ", Koschmieder " << expected);
    CHECK(measured == Approx(expected).margin(0.02));
    CHECK(wall > wall_clear);  // fog brightens a dark wall toward the airlight
  }
}

TEST_CASE("FisheyeStereo: same seed, same images, whatever the thread count", "[sensors]") {
  FisheyeStereoConfig c;
  c.width_px = 160;
  c.height_px = 120;
  c.fx_px = c.fy_px = 60;
  c.cx_px = 80;
  c.cy_px = 60;
  c.pose.position_m = {-5, 0, 1.5};
  core::WorldGeometry world;
  world.meshes = {Ground(), Box({5, 0, 3}, 2.0, core::kMaterialConcrete)};
  RaycastScene scene(world);
  FisheyeStereo camera(c, scene);
  core::WeatherConfig rain;
  rain.rain_mm_h = 40;
  auto capture = [&](std::uint64_t seed, int threads) {
    camera.set_max_threads(threads);
    core::RngStream noise(seed, "camera");
    return camera.Capture(0.0, rain, noise);
  };
  const StereoFrame a = capture(7, 0), b = capture(7, 1), d = capture(7, 2), e = capture(8, 0);
  CHECK(a.left.pixels == b.left.pixels);
  CHECK(a.right.pixels == b.right.pixels);
  CHECK(a.left.pixels == d.left.pixels);
  CHECK(a.left.pixels != e.left.pixels);
  CHECK(a.left.pixels != a.right.pixels);  // each eye has its own noise and viewpoint
  // Successive frames from one stream differ (fresh noise every frame).
  core::RngStream noise(7, "camera");
  const StereoFrame f1 = camera.Capture(0.0, rain, noise);
  const StereoFrame f2 = camera.Capture(0.0, rain, noise);
  CHECK(f1.left.pixels == a.left.pixels);
  CHECK(f1.left.pixels != f2.left.pixels);
  CHECK(a.RawBytes() == static_cast<std::size_t>(2 * 160 * 120));
  CHECK(c.RawBytesPerFrame() == a.RawBytes());
}

TEST_CASE("FisheyeStereo: night is dark and noisy", "[sensors]") {
  FisheyeStereoConfig c;
  c.width_px = 320;
  c.height_px = 240;
  c.fx_px = c.fy_px = 115;
  c.cx_px = 160;
  c.cy_px = 120;
  c.pose.position_m = {0, 0, 1.5};
  c.pose.rpy_deg = {0, -30, 0};
  core::WorldGeometry world;
  world.meshes = {Ground(), Box({20, 5, 5}, 10.0, core::kMaterialConcrete)};
  core::WeatherConfig day, night;
  night.illumination = 0.01;
  // Relative noise: the spread of the difference of two frames (which
  // cancels the scene) in a sky patch, over the patch's mean.
  auto relative_noise = [&](const core::WeatherConfig& w) {
    const StereoFrame f1 = Render(c, world, w, 1), f2 = Render(c, world, w, 2);
    double s = 0, s2 = 0, mean = 0;
    int n = 0;
    for (int v = 20; v < 40; ++v)
      for (int u = 150; u < 170; ++u) {
        const double d = double(f1.left.at(u, v)) - f2.left.at(u, v);
        s += d;
        s2 += d * d;
        mean += f1.left.at(u, v);
        ++n;
      }
    const double sd = std::sqrt(std::max(0.0, s2 / n - (s / n) * (s / n)) / 2);
    return sd / (mean / n);
  };
  const double day_mean = Mean(Render(c, world, day, 1).left);
  const double night_mean = Mean(Render(c, world, night, 1).left);
  INFO("mean day " << day_mean << ", night " << night_mean);
  CHECK(night_mean < 0.25 * day_mean);  // 0.01^(1/2.2) = 0.12
  const double day_noise = relative_noise(day), night_noise = relative_noise(night);
  INFO("relative noise day " << day_noise << ", night " << night_noise);
  CHECK(night_noise > 3 * day_noise);
}

TEST_CASE("FisheyeStereo: each pixel's noise is shot plus read noise of its radiance's electrons",
          "[sensors]") {
  // The sensor model written out independently: a pixel of linear radiance L
  // holds L * full_well electrons; shot and read noise make its count
  // Normal(L fw, L fw + read^2); with gamma 1 the 8-bit value is that count
  // over fw, clipped to [0, 1], times 255 (two roundings: 1/65535 and
  // 1/255, the second's variance 1/12 DN^2). Over many frames each pixel's
  // standardised residual must have mean 0 and variance 1.
  FisheyeStereoConfig c;
  c.width_px = 96;
  c.height_px = 72;
  c.fx_px = c.fy_px = 35;
  c.cx_px = 48;
  c.cy_px = 36;
  c.pose.position_m = {0, 0, 1.5};
  c.pose.rpy_deg = {0, -10, 0};
  c.gamma = 1.0;
  c.full_well_e = 2000.0;
  c.read_noise_e = 12.0;
  c.sensor_noise = true;
  core::WorldGeometry world;
  world.meshes = {Ground(), Box({15, 3, 4}, 6.0, core::kMaterialConcrete)};
  RaycastScene scene(world);
  FisheyeStereo camera(c, scene);
  const core::WeatherConfig day;
  const std::vector<float> radiance = camera.CaptureRadiance(0.0, day);
  const std::size_t pixels = static_cast<std::size_t>(c.width_px) * c.height_px;
  REQUIRE(radiance.size() == 2 * pixels);
  core::RngStream noise(11, "camera");
  constexpr int kFrames = 60;
  double sum = 0, sum2 = 0, count = 0;
  std::vector<double> first_frame;
  for (int f = 0; f < kFrames; ++f) {
    const StereoFrame frame = camera.Capture(0.0, day, noise);
    for (int eye = 0; eye < 2; ++eye) {
      const GrayImage& image = eye == 0 ? frame.left : frame.right;
      for (std::size_t i = 0; i < pixels; ++i) {
        const double L = radiance[eye * pixels + i];
        const double electrons = L * c.full_well_e;
        const double sd = std::sqrt(electrons + c.read_noise_e * c.read_noise_e) / c.full_well_e;
        if (L - 5 * sd < 0.02 || L + 5 * sd > 0.98) continue;  // away from clipping
        const double variance = sd * sd + 1.0 / (12.0 * 255.0 * 255.0);
        const double z = (image.pixels[i] / 255.0 - L) / std::sqrt(variance);
        sum += z;
        sum2 += z * z;
        ++count;
      }
    }
  }
  INFO("standardised residuals: " << count << " pixel-frames, mean " << sum / count << ", variance "
                                  << sum2 / count - (sum / count) * (sum / count));
  REQUIRE(count > 100000);
  const double mean = sum / count, variance = sum2 / count - mean * mean;
  // Independent pixels: the mean's std is 1 / sqrt(n); the variance's about
  // sqrt(2 / n); 1/255 quantisation of a Gaussian adds no bias beyond
  // Sheppard's 1/12 (taken into account above).
  CHECK(std::abs(mean) < 5.0 / std::sqrt(count));
  CHECK(std::abs(variance - 1.0) < 0.02);
}

TEST_CASE("FisheyeStereo: pixels outside the lens's field are black", "[sensors]") {
  FisheyeStereoConfig c;
  c.width_px = 320;
  c.height_px = 240;
  c.xi = 1.6;
  c.fx_px = c.fy_px = 120;
  c.cx_px = 160;
  c.cy_px = 120;
  core::WorldGeometry world;
  world.meshes = {Ground()};
  const StereoFrame f = Render(c, world, {}, 1);
  // r^2 = 1 / (xi^2 - 1) = 0.64: a disc of 96 px radius.
  CHECK(f.left.at(0, 0) == 0);
  CHECK(f.right.at(319, 239) == 0);
  CHECK(f.left.at(160, 120) > 0);
  CHECK(f.left.at(160 + 90, 120) > 0);
  CHECK(f.left.at(160 + 100, 120) == 0);
}

TEST_CASE("FisheyeStereoConfig: shading and sensor keys are defaulted and range-checked",
          "[sensors]") {
  auto load = [](const char* text, FisheyeStereoConfig& c) -> std::string {
    try {
      core::FromJson(core::Json::parse(text), "s.json", "/nodes/0/sensor", c);
    } catch (const core::ConfigError& e) {
      return e.what();
    }
    return "";
  };
  FisheyeStereoConfig c;
  CHECK(load("{}", c).empty());
  CHECK(c.sensor_noise);
  CHECK(c.gamma == 2.2);
  CHECK(load(R"({"sun_elevation_deg": 10, "sensor_noise": false, "exposure": 2})", c).empty());
  CHECK(c.sun_elevation_deg == 10.0);
  CHECK_FALSE(c.sensor_noise);
  CHECK(c.exposure == 2.0);
  CHECK(load(R"({"gamma": 5})", c) ==
        "s.json: /nodes/0/sensor/gamma: expected a number in [1, 3], got 5");
  CHECK(load(R"({"exposure": 0})", c) ==
        "s.json: /nodes/0/sensor/exposure: expected a number in (0, 10000], got 0");
  CHECK(load(R"({"read_noise_e": -1})", c) ==
        "s.json: /nodes/0/sensor/read_noise_e: expected a number in [0, 10000], got -1");
  CHECK(load(R"({"sun_elevation_deg": 91})", c) ==
        "s.json: /nodes/0/sensor/sun_elevation_deg: expected a number in [-90, 90], got 91");
  const core::Json written = core::ToJson(FisheyeStereoConfig{});
  for (const char* key : {"sun_azimuth_deg", "sun_elevation_deg", "exposure", "full_well_e",
                          "read_noise_e", "gamma", "sensor_noise"})
    CHECK(written.contains(key));
}

TEST_CASE("EncodePng: lossless round trip through OpenCV's decoder", "[sensors]") {
  GrayImage image;
  image.width = 37;
  image.height = 11;
  for (int i = 0; i < 37 * 11; ++i) image.pixels.push_back(static_cast<std::uint8_t>(i * 7));
  const std::vector<std::uint8_t> png = EncodePng(image);
  REQUIRE(png.size() > 8);
  CHECK(png[1] == 'P');
  CHECK(png[2] == 'N');
  CHECK(png[3] == 'G');
  const cv::Mat decoded = cv::imdecode(png, cv::IMREAD_UNCHANGED);
  REQUIRE(decoded.type() == CV_8UC1);
  REQUIRE(decoded.cols == 37);
  REQUIRE(decoded.rows == 11);
  for (int v = 0; v < 11; ++v)
    for (int u = 0; u < 37; ++u) CHECK(decoded.at<std::uint8_t>(v, u) == image.at(u, v));

  image.pixels.pop_back();
  CHECK_THROWS_WITH(EncodePng(image), Catch::Contains("37 x 11 px has 406 bytes"));
}

}  // namespace
}  // namespace uavsim::sensors
