// CameraPreprocessor against independent references: cv::omnidir's
// projection (and sensors::FisheyeModel for the k3 extension) for the
// rectification, the pinhole projection of a known 3-D point for the ROI,
// and closed-form stereo geometry for the bearings.
#include <Eigen/Geometry>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <opencv2/ccalib/omnidir.hpp>
#include <opencv2/core.hpp>
#include <vector>

#include "core/rng.h"
#include "pipeline/node/camera_preprocessor.h"
#include "sensors/fisheye_model.h"

namespace uavsim::pipeline {
namespace {

using Eye = CameraPreprocessor::Eye;

sensors::FisheyeStereoConfig DistortedCamera() {
  sensors::FisheyeStereoConfig c;
  c.xi = 0.9;
  c.fx_px = 240.0;
  c.fy_px = 236.0;
  c.cx_px = 322.5;
  c.cy_px = 238.0;
  c.k1 = -0.12;
  c.k2 = 0.03;
  c.p1 = 4e-4;
  c.p2 = -3e-4;
  return c;
}

// cv::omnidir::projectPoints of a point given in an eye's optical frame.
Eigen::Vector2d OmnidirProject(const sensors::FisheyeStereoConfig& c, const Eigen::Vector3d& p_C) {
  const std::vector<cv::Vec3d> object{{p_C.x(), p_C.y(), p_C.z()}};
  std::vector<cv::Vec2d> image;
  const cv::Matx33d K(c.fx_px, 0.0, c.cx_px, 0.0, c.fy_px, c.cy_px, 0.0, 0.0, 1.0);
  cv::omnidir::projectPoints(object, image, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(K),
                             c.xi, cv::Mat(cv::Vec4d(c.k1, c.k2, c.p1, c.p2)));
  return {image[0][0], image[0][1]};
}

// The pinhole K_new projection of p_C in the rectified view.
Eigen::Vector2d PinholeProject(const CameraPreprocessor& pre, const Eigen::Vector3d& p_C) {
  return pre.rectified_focal_px() * p_C.head<2>() / p_C.z() + pre.rectified_principal_px();
}

// Ray through rectified pixel (u, v) in the optical frame (z = 1).
Eigen::Vector3d PinholeRay(const CameraPreprocessor& pre, double u, double v) {
  const Eigen::Vector2d c = pre.rectified_principal_px();
  return {(u - c.x()) / pre.rectified_focal_px(), (v - c.y()) / pre.rectified_focal_px(), 1.0};
}

sensors::GrayImage Blank(int w, int h, std::uint8_t value) {
  sensors::GrayImage g;
  g.width = w;
  g.height = h;
  g.pixels.assign(static_cast<std::size_t>(w) * h, value);
  return g;
}

// Intensity-weighted centroid of the pixels above `floor` within `radius`
// of `around`.
Eigen::Vector2d BrightCentroid(const sensors::GrayImage& g, const Eigen::Vector2d& around,
                               int radius, int floor) {
  double sw = 0.0, su = 0.0, sv = 0.0;
  const int u0 = static_cast<int>(std::lround(around.x())),
            v0 = static_cast<int>(std::lround(around.y()));
  for (int v = std::max(0, v0 - radius); v <= std::min(g.height - 1, v0 + radius); ++v)
    for (int u = std::max(0, u0 - radius); u <= std::min(g.width - 1, u0 + radius); ++u) {
      const double w = std::max(0, g.at(u, v) - floor);
      sw += w;
      su += w * u;
      sv += w * v;
    }
  return sw > 0.0 ? Eigen::Vector2d(su / sw, sv / sw) : Eigen::Vector2d(-1e9, -1e9);
}

TEST_CASE("CameraPreprocessor: rectification map is cv::omnidir's projection of the K_new ray",
          "[pipeline]") {
  const sensors::FisheyeStereoConfig camera = DistortedCamera();
  const CameraPreprocessor pre(camera, PreprocessConfig{});
  double worst_px = 0.0;
  for (int v = 0; v < pre.rectified_height_px(); v += 23)
    for (int u = 0; u < pre.rectified_width_px(); u += 29) {
      const Eigen::Vector3d p_C = 7.5 * PinholeRay(pre, u, v);
      worst_px =
          std::max(worst_px, (pre.FisheyePixelOf(u, v) - OmnidirProject(camera, p_C)).norm());
    }
  CHECK(worst_px < 1e-3);
}

TEST_CASE("CameraPreprocessor: a point imaged by cv::omnidir lands at its K_new projection",
          "[pipeline]") {
  // A Gaussian spot drawn where cv::omnidir::projectPoints puts each world
  // point; after rectification its centroid must sit where the pinhole K_new
  // projects the point.
  const sensors::FisheyeStereoConfig camera = DistortedCamera();
  const CameraPreprocessor pre(camera, PreprocessConfig{});
  const Eigen::Isometry3d X_CW = pre.X_WC(Eye::kLeft).inverse();
  int tested = 0;
  for (double az_deg : {-40.0, -15.0, 0.0, 20.0, 45.0})
    for (double el_deg : {-30.0, 0.0, 25.0}) {
      const double az = az_deg * M_PI / 180.0, el = el_deg * M_PI / 180.0;
      // World ENU; the default pose looks along +x from the origin.
      const Eigen::Vector3d p_W = 12.0 * Eigen::Vector3d(std::cos(el) * std::cos(az),
                                                         std::cos(el) * std::sin(az), std::sin(el));
      const Eigen::Vector3d p_C = X_CW * p_W;
      const Eigen::Vector2d fisheye_px = OmnidirProject(camera, p_C);
      sensors::GrayImage image = Blank(camera.width_px, camera.height_px, 0);
      const double sigma_px = 1.5;
      for (int v = 0; v < image.height; ++v)
        for (int u = 0; u < image.width; ++u) {
          const double d2 = (Eigen::Vector2d(u, v) - fisheye_px).squaredNorm();
          if (d2 > 100.0) continue;
          image.pixels[static_cast<std::size_t>(v) * image.width + u] = static_cast<std::uint8_t>(
              std::lround(250.0 * std::exp(-0.5 * d2 / (sigma_px * sigma_px))));
        }
      const Eigen::Vector2d expected = PinholeProject(pre, p_C);
      const sensors::GrayImage rect = pre.Rectify(image);
      const Eigen::Vector2d found = BrightCentroid(rect, expected, 12, 8);
      INFO("az " << az_deg << " el " << el_deg << ": expected " << expected.transpose()
                 << ", found " << found.transpose());
      CHECK((found - expected).norm() < 0.5);
      ++tested;
    }
  CHECK(tested == 15);
}

TEST_CASE("CameraPreprocessor: the k3 extension is rectified as sensors::FisheyeModel projects",
          "[pipeline]") {
  sensors::FisheyeStereoConfig camera = DistortedCamera();
  camera.k3 = -0.004;
  const CameraPreprocessor pre(camera, PreprocessConfig{});
  const sensors::FisheyeModel model(camera);
  double worst_px = 0.0;
  int tested = 0;
  for (int v = 0; v < pre.rectified_height_px(); v += 31)
    for (int u = 0; u < pre.rectified_width_px(); u += 37) {
      const auto px = model.Project(PinholeRay(pre, u, v));
      if (!px) continue;
      worst_px = std::max(worst_px, (pre.FisheyePixelOf(u, v) - *px).norm());
      ++tested;
    }
  CHECK(tested > 200);
  CHECK(worst_px < 1e-3);
}

// A synthetic stereo sequence: a static textured wall 20 m ahead of a
// camera at the default intrinsics, sensor noise, and a dark disc drawn in
// each eye where cv::omnidir::projectPoints puts a 3-D point moving across
// the view at 3 m to 3.5 m.
class SyntheticSequence {
 public:
  static constexpr int kFrames = 45;

  SyntheticSequence() {
    camera_.pose.position_m = Eigen::Vector3d(1.0, -2.0, 1.5);
    camera_.pose.rpy_deg = Eigen::Vector3d(0.0, -10.0, 30.0);
    // Eye poses as sensors/fisheye_stereo.h defines them: optical frame
    // x_C = -y_B, y_C = -z_B, z_C = x_B; right eye baseline_m along +x_C.
    Eigen::Matrix3d R_BC;
    R_BC << 0, 0, 1, -1, 0, 0, 0, -1, 0;
    X_WC_[0] = camera_.pose.ToIsometry();
    X_WC_[0].linear() = X_WC_[0].linear() * R_BC;
    X_WC_[1] = X_WC_[0];
    X_WC_[1].translation() += camera_.baseline_m * X_WC_[0].linear().col(0);
    // The wall is fixed in the left eye's frame: z_C = 20 m.
    const sensors::FisheyeModel model(camera_);
    for (int eye = 0; eye < 2; ++eye) {
      background_[eye] = Blank(camera_.width_px, camera_.height_px, 0);
      const double offset_x = eye == 0 ? 0.0 : camera_.baseline_m;
      for (int v = 0; v < camera_.height_px; ++v)
        for (int u = 0; u < camera_.width_px; ++u) {
          const Eigen::Vector3d d = model.Unproject(u, v);
          double value = 90.0;  // "sky" where the ray misses the wall
          if (d.z() > 1e-3) {
            const double t = 20.0 / d.z();
            const double x = offset_x + t * d.x(), y = t * d.y();
            value = 140.0 + 45.0 * std::sin(1.7 * x + 0.5 * y) * std::cos(1.1 * y - 0.8 * x) +
                    25.0 * std::sin(4.3 * x) * std::sin(3.7 * y);
          }
          background_[eye].pixels[static_cast<std::size_t>(v) * camera_.width_px + u] =
              static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L));
        }
    }
  }

  const sensors::FisheyeStereoConfig& camera() const { return camera_; }
  const Eigen::Isometry3d& X_WC(int eye) const { return X_WC_[eye]; }

  // The moving point, in the world frame.
  Eigen::Vector3d TargetW(int frame) const {
    const double s = static_cast<double>(frame) / (kFrames - 1);
    const Eigen::Vector3d p_C(-0.9 + 1.8 * s, -0.35 + 0.6 * s, 3.0 + 0.5 * s);
    return X_WC_[0] * p_C;
  }

  Eigen::Vector3d InEye(int eye, const Eigen::Vector3d& p_W) const {
    return X_WC_[eye].inverse() * p_W;
  }

  // A second, smaller point, moving the other way 0.2-1 m from the first
  // (Frame's `second`).
  Eigen::Vector3d SecondW(int frame) const {
    const double s = static_cast<double>(frame) / (kFrames - 1);
    const Eigen::Vector3d p_C(0.8 - 0.6 * s, 0.45, 3.5 - 0.3 * s);
    return X_WC_[0] * p_C;
  }

  sensors::StereoFrame Frame(int frame, bool second = false) const {
    core::RngStream noise(7, "preprocess_camera_test/frame" + std::to_string(frame));
    sensors::StereoFrame out;
    out.t_capture_s = frame / 30.0;
    sensors::GrayImage* eyes[2] = {&out.left, &out.right};
    for (int eye = 0; eye < 2; ++eye) {
      sensors::GrayImage image = background_[eye];
      DrawDisc(image, OmnidirProject(camera_, InEye(eye, TargetW(frame))), kDiscRadiusPx);
      if (second)
        DrawDisc(image, OmnidirProject(camera_, InEye(eye, SecondW(frame))), kSecondRadiusPx);
      for (auto& px : image.pixels)
        px = static_cast<std::uint8_t>(
            std::clamp(std::lround(px + noise.Normal(0.0, 2.0)), 0L, 255L));
      *eyes[eye] = std::move(image);
    }
    return out;
  }

  // A dark disc of radius_px at c, its edge pixels shaded by 4 x 4 coverage.
  static void DrawDisc(sensors::GrayImage& image, const Eigen::Vector2d& c, double radius_px) {
    for (int v = std::max(0, static_cast<int>(c.y()) - 5);
         v <= std::min(image.height - 1, static_cast<int>(c.y()) + 5); ++v)
      for (int u = std::max(0, static_cast<int>(c.x()) - 5);
           u <= std::min(image.width - 1, static_cast<int>(c.x()) + 5); ++u) {
        int inside = 0;
        for (int j = 0; j < 4; ++j)
          for (int i = 0; i < 4; ++i)
            inside += (Eigen::Vector2d(u - 0.375 + 0.25 * i, v - 0.375 + 0.25 * j) - c).norm() <
                      radius_px;
        auto& px = image.pixels[static_cast<std::size_t>(v) * image.width + u];
        px = static_cast<std::uint8_t>(std::lround((px * (16 - inside) + 20.0 * inside) / 16.0));
      }
  }

  static constexpr double kDiscRadiusPx = 3.0;
  static constexpr double kSecondRadiusPx = 2.0;

 private:
  sensors::FisheyeStereoConfig camera_;
  Eigen::Isometry3d X_WC_[2];
  sensors::GrayImage background_[2];
};

const SyntheticSequence& Sequence() {
  static const SyntheticSequence sequence;
  return sequence;
}

// Midpoint of the shortest segment between two rays.
Eigen::Vector3d Triangulate(const Eigen::Vector3d& o1, const Eigen::Vector3d& d1,
                            const Eigen::Vector3d& o2, const Eigen::Vector3d& d2) {
  const Eigen::Vector3d w = o1 - o2;
  const double a = d1.dot(d1), b = d1.dot(d2), c = d2.dot(d2), d = d1.dot(w), e = d2.dot(w);
  const double den = a * c - b * b;
  const double s = (b * e - c * d) / den, t = (a * e - b * d) / den;
  return 0.5 * (o1 + s * d1 + o2 + t * d2);
}

TEST_CASE("CameraPreprocessor: ROI follows a moving target and its bearings triangulate it",
          "[pipeline]") {
  const SyntheticSequence& seq = Sequence();
  const PreprocessConfig config;
  CameraPreprocessor pre(seq.camera(), config);
  const double f = pre.rectified_focal_px(), b = seq.camera().baseline_m;
  int detected = 0;
  for (int k = 0; k < SyntheticSequence::kFrames; ++k) {
    const CameraObservation obs = pre.Process(seq.Frame(k));
    REQUIRE(obs.crop_left.size() == static_cast<std::size_t>(128 * 128));
    REQUIRE(obs.crop_right.size() == static_cast<std::size_t>(128 * 128));
    CHECK(obs.t_s == Approx(k / 30.0));
    if (k < config.camera.warmup_frames) {
      CHECK_FALSE(obs.detected);
      continue;
    }
    INFO("frame " << k);
    REQUIRE(obs.detected);
    ++detected;
    const Eigen::Vector3d p_W = seq.TargetW(k);
    const Eigen::Vector2d expected_left = PinholeProject(pre, seq.InEye(0, p_W));
    const Eigen::Vector2d expected_right = PinholeProject(pre, seq.InEye(1, p_W));
    const double left_px = (obs.centre_left_px.cast<double>() - expected_left).norm();
    const double right_px = (obs.centre_right_px.cast<double>() - expected_right).norm();
    CHECK(left_px < 2.0);
    CHECK(right_px < 2.0);
    CHECK(obs.side_left_px >= config.camera.min_roi_side_px);
    CHECK(obs.side_right_px == obs.side_left_px);
    // The crop's centre shows the dark target against the brighter wall.
    const auto centre_value = [](const std::vector<float>& crop) { return crop[64 * 128 + 64]; };
    CHECK(centre_value(obs.crop_left) < 0.3f);
    CHECK(centre_value(obs.crop_right) < 0.3f);

    CHECK((obs.eye_left_w - seq.X_WC(0).translation()).norm() < 1e-12);
    CHECK((obs.eye_right_w - seq.X_WC(1).translation()).norm() < 1e-12);
    const Eigen::Vector3d tri =
        Triangulate(obs.eye_left_w, obs.bearing_left_w, obs.eye_right_w, obs.bearing_right_w);
    // Expected stereo error for centres good to 0.25 px in each eye (0.5 px
    // of disparity): depth Z^2 dd / (f b), lateral Z dd / f.
    const double Z = seq.InEye(0, p_W).z(), dd = 0.5;
    const double depth_m = Z * Z * dd / (f * b), lateral_m = Z * dd / f;
    const double expected_m = std::hypot(depth_m, lateral_m);
    const double error_m = (tri - p_W).norm();
    INFO("triangulation error " << error_m << " m, expected " << expected_m << " m");
    CHECK(error_m < expected_m);
  }
  CHECK(detected == SyntheticSequence::kFrames - config.camera.warmup_frames);
}

TEST_CASE("CameraPreprocessor: max_observations sends the further blob, located in both eyes",
          "[pipeline]") {
  const SyntheticSequence& seq = Sequence();
  PreprocessConfig one;
  PreprocessConfig several = one;
  several.max_observations = 3;
  CameraPreprocessor pre_one(seq.camera(), one), pre(seq.camera(), several);
  int found = 0;
  for (int k = 0; k < SyntheticSequence::kFrames; ++k) {
    std::vector<CameraObservation> further, none;
    const CameraObservation obs = pre.Process(seq.Frame(k, true), &further);
    // The picked observation is what max_observations 1 gives.
    const CameraObservation alone = pre_one.Process(seq.Frame(k, true), &none);
    CHECK(none.empty());
    CHECK(obs.detected == alone.detected);
    CHECK(obs.centre_left_px == alone.centre_left_px);
    CHECK(obs.crop_left == alone.crop_left);
    if (k < several.camera.warmup_frames) {
      CHECK(further.empty());
      continue;
    }
    INFO("frame " << k);
    REQUIRE(obs.detected);
    CHECK((obs.centre_left_px.cast<double>() - PinholeProject(pre, seq.InEye(0, seq.TargetW(k))))
              .norm() < 2.0);
    REQUIRE(further.size() <= 2);
    if (further.empty()) continue;
    ++found;
    const CameraObservation& o = further.front();
    CHECK(o.detected);
    CHECK(o.t_s == obs.t_s);
    const Eigen::Vector3d p_W = seq.SecondW(k);
    CHECK((o.centre_left_px.cast<double>() - PinholeProject(pre, seq.InEye(0, p_W))).norm() < 2.0);
    CHECK((o.centre_right_px.cast<double>() - PinholeProject(pre, seq.InEye(1, p_W))).norm() < 2.0);
    CHECK(o.crop_left.size() == static_cast<std::size_t>(128 * 128));
    const Eigen::Vector3d tri =
        Triangulate(o.eye_left_w, o.bearing_left_w, o.eye_right_w, o.bearing_right_w);
    // As the first test's bound, for centres good to 0.5 px (a smaller disc).
    const double f = pre.rectified_focal_px(), b = seq.camera().baseline_m;
    const double Z = seq.InEye(0, p_W).z(), dd = 1.0;
    CHECK((tri - p_W).norm() < std::hypot(Z * Z * dd / (f * b), Z * dd / f));
  }
  // The second point is found in most frames after the warm-up.
  CHECK(found >= (SyntheticSequence::kFrames - several.camera.warmup_frames) * 3 / 4);
}

TEST_CASE("CameraPreprocessor: deterministic, whatever OpenCV's thread count", "[pipeline]") {
  const SyntheticSequence& seq = Sequence();
  const int threads = cv::getNumThreads();
  std::vector<CameraObservation> runs[2];
  for (int run = 0; run < 2; ++run) {
    cv::setNumThreads(run == 0 ? 1 : 2);
    CameraPreprocessor pre(seq.camera(), PreprocessConfig{});
    for (int k = 0; k < 22; ++k) runs[run].push_back(pre.Process(seq.Frame(k)));
  }
  cv::setNumThreads(threads);
  for (std::size_t k = 0; k < runs[0].size(); ++k) {
    const CameraObservation &a = runs[0][k], &b = runs[1][k];
    CHECK(a.detected == b.detected);
    CHECK(a.crop_left == b.crop_left);
    CHECK(a.crop_right == b.crop_right);
    CHECK(a.centre_left_px == b.centre_left_px);
    CHECK(a.centre_right_px == b.centre_right_px);
    CHECK(a.bearing_left_w == b.bearing_left_w);
    CHECK(a.bearing_right_w == b.bearing_right_w);
  }
  // Reset forgets the background: the first frames are warm-up again.
  CameraPreprocessor pre(seq.camera(), PreprocessConfig{});
  for (int k = 0; k < 20; ++k) pre.Process(seq.Frame(k));
  pre.Reset();
  CHECK_FALSE(pre.Process(seq.Frame(20)).detected);
}

TEST_CASE("CameraPreprocessor: no moving target, no detection", "[pipeline]") {
  const SyntheticSequence& seq = Sequence();
  CameraPreprocessor pre(seq.camera(), PreprocessConfig{});
  // The same frame over and over: after warm-up nothing moves.
  const sensors::StereoFrame still = seq.Frame(0);
  for (int k = 0; k < 30; ++k) {
    const CameraObservation obs = pre.Process(still);
    CHECK_FALSE(obs.detected);
    CHECK(
        std::all_of(obs.crop_left.begin(), obs.crop_left.end(), [](float x) { return x == 0.0f; }));
    CHECK(obs.centre_left_px == Eigen::Vector2f::Zero());
  }
}

TEST_CASE("CameraPreprocessor: raw variant is the whole image at 128 x 128", "[pipeline]") {
  const SyntheticSequence& seq = Sequence();
  PreprocessConfig config;
  config.raw = true;
  CameraPreprocessor pre(seq.camera(), config);
  const sensors::StereoFrame frame = seq.Frame(3);
  const CameraObservation obs = pre.Process(frame);  // no warm-up
  CHECK(obs.detected);
  REQUIRE(obs.crop_left.size() == static_cast<std::size_t>(128 * 128));
  REQUIRE(obs.crop_right.size() == static_cast<std::size_t>(128 * 128));
  CHECK(obs.centre_left_px == Eigen::Vector2f(319.5f, 239.5f));
  CHECK(obs.centre_right_px == Eigen::Vector2f(319.5f, 239.5f));
  CHECK(obs.side_left_px == 640.0f);
  CHECK(obs.side_right_px == 640.0f);
  // Area averaging keeps the image's mean grey level.
  double image_mean = 0.0, crop_mean = 0.0;
  for (auto px : frame.left.pixels) image_mean += px / 255.0;
  for (float x : obs.crop_left) {
    CHECK(x >= 0.0f);
    CHECK(x <= 1.0f);
    crop_mean += x;
  }
  CHECK(crop_mean / obs.crop_left.size() ==
        Approx(image_mean / frame.left.pixels.size()).margin(2e-3));
  // Bearings are the optical axes.
  CHECK((obs.bearing_left_w - pre.X_WC(Eye::kLeft).linear().col(2)).norm() < 1e-12);

  // Only the camera raw: the per-modality switch.
  PreprocessConfig camera_only;
  camera_only.camera.raw = true;
  CHECK(camera_only.CameraRaw());
  CHECK_FALSE(camera_only.LidarRaw());
  CHECK_FALSE(camera_only.RadarRaw());
}

TEST_CASE("CameraPreprocessor: a wrongly sized eye is refused", "[pipeline]") {
  CameraPreprocessor pre(sensors::FisheyeStereoConfig{}, PreprocessConfig{});
  sensors::StereoFrame frame;
  frame.left = Blank(640, 480, 0);
  frame.right = Blank(320, 240, 0);
  CHECK_THROWS_WITH(pre.Process(frame),
                    Catch::Contains("right image is 320 x 240") && Catch::Contains("640 x 480"));
}

}  // namespace
}  // namespace uavsim::pipeline
