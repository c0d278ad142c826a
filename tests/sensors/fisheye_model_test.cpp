// FisheyeModel against the independent reference, OpenCV's cv::omnidir
// (Mei's unified model as opencv_contrib implements it).
#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <opencv2/ccalib/omnidir.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/rng.h"
#include "sensors/fisheye_model.h"

namespace uavsim::sensors {
namespace {

FisheyeStereoConfig Intrinsics(int w, int h, double xi, double fx, double fy, double cx, double cy,
                               double k1, double k2, double p1, double p2) {
  FisheyeStereoConfig c;
  c.width_px = w;
  c.height_px = h;
  c.xi = xi;
  c.fx_px = fx;
  c.fy_px = fy;
  c.cx_px = cx;
  c.cy_px = cy;
  c.k1 = k1;
  c.k2 = k2;
  c.p1 = p1;
  c.p2 = p2;
  return c;
}

// Parameter sets: the default lens, moderate and strong distortion, xi
// below, at and above 1 (above 1 the image of the sphere is a disc), and
// xi = 0 (a pinhole with Brown-Conrady distortion).
std::vector<FisheyeStereoConfig> ParameterSets() {
  return {
      Intrinsics(640, 480, 1.0, 230, 230, 320, 240, 0, 0, 0, 0),
      Intrinsics(640, 480, 0.8, 300, 290, 330.5, 235.25, -0.25, 0.06, 1e-3, -8e-4),
      Intrinsics(1280, 960, 1.6, 500, 505, 640.2, 479.7, -0.05, 0.01, -2e-3, 1.5e-3),
      Intrinsics(800, 600, 0.0, 400, 400, 401, 298, 0.1, -0.02, 5e-4, 3e-4),
      Intrinsics(752, 480, 2.2, 1100, 1090, 370, 245, -0.3, 0.2, 2e-3, 1e-3),
  };
}

std::string Describe(const FisheyeStereoConfig& c) {
  return "xi=" + std::to_string(c.xi) + " k1=" + std::to_string(c.k1) +
         " k2=" + std::to_string(c.k2) + " p1=" + std::to_string(c.p1) +
         " p2=" + std::to_string(c.p2) + " k3=" + std::to_string(c.k3);
}

cv::Matx33d CameraMatrix(const FisheyeStereoConfig& c) {
  return {c.fx_px, 0.0, c.cx_px, 0.0, c.fy_px, c.cy_px, 0.0, 0.0, 1.0};
}

cv::Vec4d DistortionVector(const FisheyeStereoConfig& c) { return {c.k1, c.k2, c.p1, c.p2}; }

// cv::omnidir::projectPoints of points already in the camera frame.
std::vector<cv::Vec2d> OpenCvProject(const FisheyeStereoConfig& c,
                                     const std::vector<Eigen::Vector3d>& p_C) {
  std::vector<cv::Vec3d> object;
  for (const auto& p : p_C) object.emplace_back(p.x(), p.y(), p.z());
  std::vector<cv::Vec2d> image;
  cv::omnidir::projectPoints(object, image, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0),
                             cv::Mat(CameraMatrix(c)), c.xi, cv::Mat(DistortionVector(c)));
  return image;
}

Eigen::Vector3d RandomUnitVector(core::RngStream& rng) {
  Eigen::Vector3d d(rng.Normal(), rng.Normal(), rng.Normal());
  return d.normalized();
}

double AngleRad(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

TEST_CASE("FisheyeModel: projection matches cv::omnidir::projectPoints", "[sensors]") {
  core::RngStream rng(42, "fisheye_model_test/project");
  for (const FisheyeStereoConfig& c : ParameterSets()) {
    INFO(Describe(c));
    const FisheyeModel model(c);
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < 20000; ++i)
      points.push_back(RandomUnitVector(rng) * rng.Uniform(0.3, 300.0));
    const std::vector<cv::Vec2d> reference = OpenCvProject(c, points);
    int compared = 0;
    double worst_px = 0.0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto px = model.Project(points[i]);
      if (!px) continue;
      ++compared;
      worst_px =
          std::max(worst_px, (*px - Eigen::Vector2d(reference[i][0], reference[i][1])).norm());
    }
    INFO("compared " << compared << " points, worst " << worst_px << " px");
    CHECK(compared >= 1000);
    CHECK(worst_px < 0.01);
  }
}

TEST_CASE("FisheyeModel: Unproject inverts Project to < 1e-6 rad", "[sensors]") {
  core::RngStream rng(42, "fisheye_model_test/roundtrip");
  // OpenCV has no k3; the inverse must hold with it too.
  std::vector<FisheyeStereoConfig> sets = ParameterSets();
  sets.push_back(Intrinsics(640, 480, 1.1, 250, 250, 320, 240, -0.2, 0.05, 1e-3, 1e-3));
  sets.back().k3 = -0.01;
  for (const FisheyeStereoConfig& c : sets) {
    INFO(Describe(c));
    const FisheyeModel model(c);
    int compared = 0;
    double worst_rad = 0.0;
    for (int i = 0; i < 20000; ++i) {
      const Eigen::Vector3d p = RandomUnitVector(rng) * rng.Uniform(0.3, 300.0);
      const auto px = model.Project(p);
      if (!px) continue;
      const Eigen::Vector3d ray = model.Unproject(px->x(), px->y());
      REQUIRE(std::abs(ray.norm() - 1.0) < 1e-12);
      worst_rad = std::max(worst_rad, AngleRad(ray, p.normalized()));
      ++compared;
    }
    INFO("compared " << compared << " points, worst " << worst_rad << " rad");
    CHECK(compared >= 1000);
    CHECK(worst_rad < 1e-6);
  }
}

TEST_CASE("FisheyeModel: Unproject agrees with cv::omnidir::undistortPoints", "[sensors]") {
  core::RngStream rng(42, "fisheye_model_test/undistort");
  for (const FisheyeStereoConfig& c : ParameterSets()) {
    INFO(Describe(c));
    const FisheyeModel model(c);
    std::vector<cv::Vec2d> pixels;
    std::vector<Eigen::Vector3d> rays;
    for (int i = 0; i < 5000; ++i) {
      const double u = rng.Uniform(-0.5, c.width_px - 0.5);
      const double v = rng.Uniform(-0.5, c.height_px - 0.5);
      const Eigen::Vector3d ray = model.Unproject(u, v);
      if (ray.isZero() || ray.z() < 0.1) continue;
      pixels.emplace_back(u, v);
      rays.push_back(ray);
    }
    CHECK(pixels.size() >= 1000);
    // OpenCV 4.6's undistortPoints returns the lifted ray on the perspective
    // plane z = 1, (x_s / z_s, y_s / z_s) (newer releases return Mei's plane,
    // x_s / (z_s + xi)): compare where z_s is clearly positive.
    std::vector<cv::Vec2d> undistorted;
    const cv::Mat xi(1, 1, CV_64F, cv::Scalar(c.xi));
    cv::omnidir::undistortPoints(pixels, undistorted, cv::Mat(CameraMatrix(c)),
                                 cv::Mat(DistortionVector(c)), xi, cv::Mat::eye(3, 3, CV_64F));
    double worst = 0.0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const Eigen::Vector2d ours = rays[i].head<2>() / rays[i].z();
      worst =
          std::max(worst, (ours - Eigen::Vector2d(undistorted[i][0], undistorted[i][1])).norm());
    }
    INFO("worst difference on the plane z = 1: " << worst);
    CHECK(worst < 1e-6);
  }
}

TEST_CASE("FisheyeModel: the ray table reprojects onto its pixel centres through OpenCV",
          "[sensors]") {
  for (const FisheyeStereoConfig& c : ParameterSets()) {
    INFO(Describe(c));
    const FisheyeModel model(c);
    const RayTable table = model.ComputeRayTable();
    REQUIRE(table.direction_C.size() == static_cast<std::size_t>(c.width_px) * c.height_px);
    std::vector<Eigen::Vector3d> rays;
    std::vector<Eigen::Vector2d> centres;
    double worst_rad = 0.0;
    for (int v = 0; v < c.height_px; v += 3) {
      for (int u = 0; u < c.width_px; u += 3) {
        const std::size_t i = static_cast<std::size_t>(v) * c.width_px + u;
        if (!table.valid[i]) continue;
        const Eigen::Vector3d ray = table.direction_C[i].cast<double>();
        rays.push_back(ray);
        centres.emplace_back(u, v);
        worst_rad = std::max(worst_rad, AngleRad(ray, model.Unproject(u, v)));
      }
    }
    REQUIRE(rays.size() > 1000);
    const std::vector<cv::Vec2d> reference = OpenCvProject(c, rays);
    double worst_px = 0.0;
    for (std::size_t i = 0; i < rays.size(); ++i)
      worst_px = std::max(worst_px,
                          (centres[i] - Eigen::Vector2d(reference[i][0], reference[i][1])).norm());
    INFO("worst " << worst_px << " px, " << worst_rad << " rad (float table vs double)");
    // A float ray carries ~6e-8 rad of rounding: 1e-6 rad leaves room, and
    // 1e-3 px is 1e-6 rad at the longest focal length here.
    CHECK(worst_rad < 1e-6);
    CHECK(worst_px < 1e-3);
  }
}

TEST_CASE("FisheyeModel: with xi > 1 the image of the sphere is a disc", "[sensors]") {
  // Without distortion the valid pixels are exactly those with
  // |m_u|^2 < 1 / (xi^2 - 1) (Mei's lifting has a real root there).
  const FisheyeStereoConfig c = Intrinsics(640, 480, 1.5, 150, 160, 320, 240, 0, 0, 0, 0);
  const RayTable table = FisheyeModel(c).ComputeRayTable();
  const double limit_r2 = 1.0 / (c.xi * c.xi - 1.0);
  int mismatches = 0, invalid = 0, on_the_rim = 0;
  for (int v = 0; v < c.height_px; ++v) {
    for (int u = 0; u < c.width_px; ++u) {
      const double x = (u - c.cx_px) / c.fx_px, y = (v - c.cy_px) / c.fy_px;
      const double r2 = x * x + y * y;
      if (std::abs(r2 - limit_r2) < 1e-9) {
        ++on_the_rim;
        continue;
      }
      const bool expected = r2 < limit_r2;
      const bool got = table.valid[static_cast<std::size_t>(v) * c.width_px + u] != 0;
      mismatches += expected != got;
      invalid += !got;
    }
  }
  CHECK(mismatches == 0);
  CHECK(invalid > 10000);  // the corners see nothing
  CHECK(table.valid_count + invalid + on_the_rim ==
        static_cast<std::size_t>(c.width_px) * c.height_px);
}

TEST_CASE("FisheyeModel: points outside the valid domain do not project", "[sensors]") {
  const FisheyeModel unit(Intrinsics(640, 480, 1.0, 230, 230, 320, 240, 0, 0, 0, 0));
  CHECK_FALSE(unit.Project(Eigen::Vector3d::Zero()));
  CHECK_FALSE(unit.Project(Eigen::Vector3d(0, 0, -5)));  // straight behind: x_s z + xi = 0
  CHECK(unit.Project(Eigen::Vector3d(0, 0, 5)));
  CHECK(unit.Project(Eigen::Vector3d(1, 0, 0)));           // 90 deg off axis: u = cx + fx
  CHECK_FALSE(unit.Project(Eigen::Vector3d(1, 0, -0.5)));  // u = 692: beyond the right edge

  const FisheyeModel half(Intrinsics(640, 480, 0.5, 100, 100, 320, 240, 0, 0, 0, 0));
  CHECK_FALSE(half.Project(Eigen::Vector3d(0.75, 0, -0.6)));           // z_s = -0.6 < -xi
  CHECK(half.Project(Eigen::Vector3d(0.9, 0, -0.3)) == std::nullopt);  // valid ray, off-image
  CHECK(half.Project(Eigen::Vector3d(0.3, 0, 1.0)));

  // k1 < 0 folds the lens where d(r (1 + k1 r^2))/dr = 0, at r^2 = -1 / (3 k1);
  // the valid domain stops 0.1 % (in r^2) short of it.
  const FisheyeModel folding(Intrinsics(4000, 4000, 0.0, 100, 100, 2000, 2000, -0.3, 0, 0, 0));
  CHECK(folding.max_undistorted_radius() == Approx(std::sqrt(0.999 / 0.9)).epsilon(1e-9));
  CHECK(folding.Project(Eigen::Vector3d(1.0, 0, 1.0)));
  CHECK_FALSE(folding.Project(Eigen::Vector3d(1.1, 0, 1.0)));
}

}  // namespace
}  // namespace uavsim::sensors
