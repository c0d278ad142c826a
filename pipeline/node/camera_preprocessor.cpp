#include "pipeline/node/camera_preprocessor.h"

#include <algorithm>
#include <cmath>
#include <opencv2/ccalib/omnidir.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/background_segm.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace uavsim::pipeline {
namespace {

constexpr int kCrop = CameraObservation::kCropPx;
// Below this contrast (grey levels) between the target and the scene behind
// a pixel, the fraction of the pixel the target covers is not observable.
constexpr double kMinContrast = 8.0;

// A read-only OpenCV view of an 8-bit image (no copy).
cv::Mat View(const sensors::GrayImage& image) {
  return cv::Mat(image.height, image.width, CV_8UC1,
                 const_cast<std::uint8_t*>(image.pixels.data()));
}

void CheckSize(const sensors::GrayImage& image, const sensors::FisheyeStereoConfig& camera,
               const char* what) {
  if (image.width != camera.width_px || image.height != camera.height_px ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * image.height)
    throw std::invalid_argument(std::string("CameraPreprocessor: ") + what + " image is " +
                                std::to_string(image.width) + " x " + std::to_string(image.height) +
                                " (" + std::to_string(image.pixels.size()) + " bytes), expected " +
                                std::to_string(camera.width_px) + " x " +
                                std::to_string(camera.height_px));
}

void ToUnitFloats(const cv::Mat& image8, std::vector<float>& out) {
  cv::Mat f;
  image8.convertTo(f, CV_32F, 1.0 / 255.0);
  out.assign(f.ptr<float>(), f.ptr<float>() + f.total());
}

// The square [cx - side/2, cx + side/2] x [cy - side/2, cy + side/2] of
// `image` (continuous coordinates; pixel k covers [k - 0.5, k + 0.5]) on a
// kCrop x kCrop grid, zero outside the image.
void Crop(const cv::Mat& image, double cx, double cy, double side, std::vector<float>& out) {
  cv::Mat crop;
  const double s = side / kCrop;
  if (s <= 2.0) {
    // Bilinear is exact enough up to 2x downsampling and keeps the sub-pixel
    // centre.
    const cv::Matx23d M(s, 0.0, cx - 0.5 * side + 0.5 * s, 0.0, s, cy - 0.5 * side + 0.5 * s);
    cv::warpAffine(image, crop, M, cv::Size(kCrop, kCrop), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                   cv::BORDER_CONSTANT, cv::Scalar(0));
  } else {
    // Larger ROIs would alias under bilinear sampling: area-average the
    // whole-pixel square instead (its centre within half a pixel of cx, cy).
    const int n = static_cast<int>(std::lround(side));
    const int x0 = static_cast<int>(std::lround(cx - 0.5 * side));
    const int y0 = static_cast<int>(std::lround(cy - 0.5 * side));
    cv::Mat square = cv::Mat::zeros(n, n, CV_8UC1);
    const cv::Rect want(x0, y0, n, n);
    const cv::Rect have = want & cv::Rect(0, 0, image.cols, image.rows);
    if (have.area() > 0) image(have).copyTo(square(have - want.tl()));
    cv::resize(square, crop, cv::Size(kCrop, kCrop), 0.0, 0.0, cv::INTER_AREA);
  }
  ToUnitFloats(crop, out);
}

// A connected foreground component of the rectified left eye.
struct Blob {
  int area_px = 0;
  cv::Rect box;  // bounding box
  Eigen::Vector2d sum_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d centroid_px() const { return sum_px / std::max(1, area_px); }
};

}  // namespace

struct CameraPreprocessor::Impl {
  sensors::FisheyeStereoConfig camera;
  CameraPreprocessConfig config;
  int max_observations = 1;
  bool raw = false;

  int width_px = 0, height_px = 0;  // rectified
  double focal_px = 0.0;
  Eigen::Vector2d principal_px = Eigen::Vector2d::Zero();
  cv::Mat map_x, map_y;                  // CV_32FC1: fisheye pixel per rectified pixel
  cv::Mat map_fixed_xy, map_fixed_frac;  // the same in remap's fast fixed-point form
  Eigen::Isometry3d X_WC[2];

  cv::Ptr<cv::BackgroundSubtractorMOG2> mog2;
  cv::Mat closing_kernel;
  int frame_index = 0;  // frames processed since construction or Reset
  bool has_previous = false;
  Eigen::Vector2d previous_centre_px = Eigen::Vector2d::Zero();
  int previous_frame = 0;

  // Running means of the rectified eyes (CV_32F), for sub-pixel location.
  cv::Mat background[2];
  // Where a left foreground pixel can appear in the right eye.
  int max_disparity_px = 0;
  cv::Mat right_spread_kernel;
  cv::Point right_spread_anchor;

  // Scratch, kept to avoid reallocating per frame.
  cv::Mat left_rect, right_rect, foreground, labels, ncc, not_learnt, learn;
  std::vector<cv::Point> foreground_px;
  std::vector<Blob> blobs;  // index = label; 0 is the background

  void BuildMaps();
  void ResetTracking();
  Eigen::Vector3d BearingW(Eye eye, const Eigen::Vector2d& centre_px) const;
  CameraObservation EmptyObservation(double t_s) const;
  CameraObservation ProcessRaw(const sensors::StereoFrame& frame) const;
  CameraObservation ProcessRoi(const sensors::StereoFrame& frame,
                               std::vector<CameraObservation>* further);
  // The selected blob into obs (and the further ones, largest first).
  void Detect(CameraObservation& obs, std::vector<CameraObservation>* further);
  // Blob `blob` located in both eyes into obs; false (obs untouched) when
  // the stereo check fails. Its left centre either way.
  bool Locate(int blob, CameraObservation& obs, Eigen::Vector2d& centre_left_px);
  std::optional<Eigen::Vector2d> CoverageCentroid(int eye, const cv::Rect& window,
                                                  const cv::Mat& mask, const cv::Mat& core,
                                                  double target_grey) const;
  void UpdateBackgrounds();
  void FindBlobs();
  int SelectBlob() const;
};

void CameraPreprocessor::Impl::BuildMaps() {
  const cv::Size size(width_px, height_px);
  const cv::Matx33d K_new(focal_px, 0.0, principal_px.x(), 0.0, focal_px, principal_px.y(), 0.0,
                          0.0, 1.0);
  if (camera.k3 == 0.0) {
    const cv::Matx33d K(camera.fx_px, 0.0, camera.cx_px, 0.0, camera.fy_px, camera.cy_px, 0.0, 0.0,
                        1.0);
    const cv::Vec4d D(camera.k1, camera.k2, camera.p1, camera.p2);
    const cv::Mat xi(1, 1, CV_64F, cv::Scalar(camera.xi));
    cv::omnidir::initUndistortRectifyMap(K, D, xi, cv::Matx33d::eye(), K_new, size, CV_32FC1, map_x,
                                         map_y, cv::omnidir::RECTIFY_PERSPECTIVE);
  } else {
    // cv::omnidir has no k3: the same forward map (ray of the rectified
    // pixel, onto the sphere, Mei's projection, distortion, K) with the
    // r^6 term, as sensors/fisheye_model.h defines the lens.
    map_x.create(size, CV_32FC1);
    map_y.create(size, CV_32FC1);
    const double xi = camera.xi, k1 = camera.k1, k2 = camera.k2, k3 = camera.k3;
    const double p1 = camera.p1, p2 = camera.p2;
    for (int v = 0; v < height_px; ++v) {
      for (int u = 0; u < width_px; ++u) {
        const Eigen::Vector3d x_s = Eigen::Vector3d((u - principal_px.x()) / focal_px,
                                                    (v - principal_px.y()) / focal_px, 1.0)
                                        .normalized();
        const double x = x_s.x() / (x_s.z() + xi), y = x_s.y() / (x_s.z() + xi);
        const double r2 = x * x + y * y;
        const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
        const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
        map_x.at<float>(v, u) = static_cast<float>(camera.fx_px * xd + camera.cx_px);
        map_y.at<float>(v, u) = static_cast<float>(camera.fy_px * yd + camera.cy_px);
      }
    }
  }
  cv::convertMaps(map_x, map_y, map_fixed_xy, map_fixed_frac, CV_16SC2);
}

void CameraPreprocessor::Impl::ResetTracking() {
  mog2 = cv::createBackgroundSubtractorMOG2(config.mog2_history_frames, config.mog2_var_threshold,
                                            /*detectShadows=*/false);
  frame_index = 0;
  has_previous = false;
  previous_frame = 0;
}

Eigen::Vector3d CameraPreprocessor::Impl::BearingW(Eye eye,
                                                   const Eigen::Vector2d& centre_px) const {
  const Eigen::Vector3d ray_C((centre_px.x() - principal_px.x()) / focal_px,
                              (centre_px.y() - principal_px.y()) / focal_px, 1.0);
  return X_WC[static_cast<int>(eye)].linear() * ray_C.normalized();
}

CameraObservation CameraPreprocessor::Impl::EmptyObservation(double t_s) const {
  CameraObservation obs;
  obs.t_s = t_s;
  obs.crop_left.assign(kCrop * kCrop, 0.0f);
  obs.crop_right.assign(kCrop * kCrop, 0.0f);
  obs.eye_left_w = X_WC[0].translation();
  obs.eye_right_w = X_WC[1].translation();
  obs.bearing_left_w = X_WC[0].linear().col(2);  // the optical axes
  obs.bearing_right_w = X_WC[1].linear().col(2);
  return obs;
}

CameraObservation CameraPreprocessor::Impl::ProcessRaw(const sensors::StereoFrame& frame) const {
  CameraObservation obs = EmptyObservation(frame.t_capture_s);
  cv::Mat small;
  cv::resize(View(frame.left), small, cv::Size(kCrop, kCrop), 0.0, 0.0, cv::INTER_AREA);
  ToUnitFloats(small, obs.crop_left);
  cv::resize(View(frame.right), small, cv::Size(kCrop, kCrop), 0.0, 0.0, cv::INTER_AREA);
  ToUnitFloats(small, obs.crop_right);
  obs.detected = true;
  const Eigen::Vector2f centre(0.5f * (camera.width_px - 1), 0.5f * (camera.height_px - 1));
  obs.centre_left_px = centre;
  obs.centre_right_px = centre;
  obs.side_left_px = static_cast<float>(camera.width_px);
  obs.side_right_px = static_cast<float>(camera.width_px);
  return obs;
}

void CameraPreprocessor::Impl::FindBlobs() {
  // connectedComponentsWithStats scans the whole image for its statistics
  // (about 4 ms at 640 x 480); the foreground is sparse, so the labels
  // alone and a pass over the foreground pixels are ten times faster.
  const int count = cv::connectedComponents(foreground, labels, 8, CV_32S);
  blobs.assign(count, Blob{});
  cv::findNonZero(foreground, foreground_px);
  for (const cv::Point& p : foreground_px) {
    Blob& b = blobs[labels.at<int>(p)];
    b.box = b.area_px == 0 ? cv::Rect(p, cv::Size(1, 1)) : b.box | cv::Rect(p, cv::Size(1, 1));
    ++b.area_px;
    b.sum_px += Eigen::Vector2d(p.x, p.y);
  }
}

int CameraPreprocessor::Impl::SelectBlob() const {
  const bool gated = config.gate_px > 0.0 && has_previous &&
                     frame_index - previous_frame <= config.gate_max_age_frames;
  int best = -1, best_gated = -1;
  int best_area = 0, best_gated_area = 0;
  for (int label = 1; label < static_cast<int>(blobs.size()); ++label) {
    const int area = blobs[label].area_px;
    if (area < config.min_blob_area_px) continue;
    if (area > best_area) best = label, best_area = area;
    if (gated && area > best_gated_area &&
        (blobs[label].centroid_px() - previous_centre_px).norm() <= config.gate_px)
      best_gated = label, best_gated_area = area;
  }
  return best_gated >= 0 ? best_gated : best;
}

CameraObservation CameraPreprocessor::Impl::ProcessRoi(const sensors::StereoFrame& frame,
                                                       std::vector<CameraObservation>* further) {
  CameraObservation obs = EmptyObservation(frame.t_capture_s);

  cv::remap(View(frame.left), left_rect, map_fixed_xy, map_fixed_frac, cv::INTER_LINEAR,
            cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::remap(View(frame.right), right_rect, map_fixed_xy, map_fixed_frac, cv::INTER_LINEAR,
            cv::BORDER_CONSTANT, cv::Scalar(0));
  mog2->apply(left_rect, foreground);
  ++frame_index;
  if (frame_index == 1) {
    left_rect.convertTo(background[0], CV_32F);
    right_rect.convertTo(background[1], CV_32F);
  }
  if (config.morphology_kernel_px > 1) {
    // Closing, not opening: a distant UAV is a blob of a few pixels that an
    // opening would erase; closing joins its fragments (body, rotors).
    cv::morphologyEx(foreground, foreground, cv::MORPH_CLOSE, closing_kernel);
  }
  if (frame_index > config.warmup_frames) Detect(obs, further);
  UpdateBackgrounds();
  return obs;
}

void CameraPreprocessor::Impl::UpdateBackgrounds() {
  // MOG2 decides what moves; these running means only serve to subtract
  // the scene behind the target when locating it to sub-pixel precision.
  // Foreground pixels are not learnt, in the right eye wherever the left
  // foreground can appear (disparity -1 to max_disparity_px, +-slack rows).
  const double alpha = 1.0 / std::min<double>(frame_index, std::max(1, config.mog2_history_frames));
  cv::dilate(foreground, not_learnt, cv::Mat());
  cv::bitwise_not(not_learnt, learn);
  cv::accumulateWeighted(left_rect, background[0], alpha, learn);
  cv::dilate(foreground, not_learnt, right_spread_kernel, right_spread_anchor);
  cv::bitwise_not(not_learnt, learn);
  cv::accumulateWeighted(right_rect, background[1], alpha, learn);
}

std::optional<Eigen::Vector2d> CameraPreprocessor::Impl::CoverageCentroid(
    int eye, const cv::Rect& window, const cv::Mat& mask, const cv::Mat& core,
    double target_grey) const {
  // Each pixel weighs by the fraction a of it the target covers, from
  // I = a T + (1 - a) B. Weighing by |I - B| instead would weigh the
  // target's pixels by the contrast of the scene behind them and pull the
  // centre toward bright texture (0.3 px on a textured wall).
  const cv::Mat& image = eye == 0 ? left_rect : right_rect;
  const cv::Mat& scene = background[eye];
  cv::Mat weight(window.size(), CV_32F, cv::Scalar(0));
  for (int r = 0; r < window.height; ++r) {
    for (int c = 0; c < window.width; ++c) {
      if (!mask.at<std::uint8_t>(r, c)) continue;
      const double b = scene.at<float>(window.y + r, window.x + c);
      const double i = image.at<std::uint8_t>(window.y + r, window.x + c);
      const double contrast = target_grey - b;
      weight.at<float>(r, c) = static_cast<float>(std::abs(contrast) < kMinContrast
                                                      ? (core.at<std::uint8_t>(r, c) ? 1.0 : 0.0)
                                                      : std::clamp((i - b) / contrast, 0.0, 1.0));
    }
  }
  const cv::Moments m = cv::moments(weight);
  if (!(m.m00 > 0.0)) return std::nullopt;
  return Eigen::Vector2d(window.x + m.m10 / m.m00, window.y + m.m01 / m.m00);
}

void CameraPreprocessor::Impl::Detect(CameraObservation& obs,
                                      std::vector<CameraObservation>* further) {
  FindBlobs();
  const int blob = SelectBlob();
  if (blob < 0) return;
  Eigen::Vector2d centre;
  Locate(blob, obs, centre);
  // The gate follows the left centre, whether or not the stereo check passed.
  has_previous = true;
  previous_centre_px = centre;
  previous_frame = frame_index;
  if (!further) return;
  // The further blobs, largest first (equal areas: the lower label).
  std::vector<int> order;
  for (int label = 1; label < static_cast<int>(blobs.size()); ++label)
    if (label != blob && blobs[label].area_px >= config.min_blob_area_px) order.push_back(label);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return blobs[a].area_px > blobs[b].area_px; });
  for (int label : order) {
    if (static_cast<int>(further->size()) + 1 >= max_observations) break;
    CameraObservation other = EmptyObservation(obs.t_s);
    Eigen::Vector2d unused;
    if (Locate(label, other, unused)) further->push_back(std::move(other));
  }
}

bool CameraPreprocessor::Impl::Locate(int blob, CameraObservation& obs,
                                      Eigen::Vector2d& centre_left_px) {
  const cv::Rect image_rect(0, 0, width_px, height_px);
  const cv::Rect box = blobs[blob].box;
  const int extent_px = std::max(box.width, box.height);

  // Sub-pixel centre: the coverage-weighted centroid over the blob and a
  // one-pixel rim (MOG2's threshold misses the target's partly covered edge
  // pixels, which carry the fraction). The target's own grey level: the
  // median over the blob, most of whose pixels it covers fully.
  const cv::Rect window = (box + cv::Size(4, 4) - cv::Point(2, 2)) & image_rect;
  const cv::Mat core = labels(window) == blob;
  cv::Mat mask;
  cv::dilate(core, mask, cv::Mat());
  std::vector<std::uint8_t> grey;
  for (int r = 0; r < window.height; ++r)
    for (int c = 0; c < window.width; ++c)
      if (core.at<std::uint8_t>(r, c))
        grey.push_back(left_rect.at<std::uint8_t>(window.y + r, window.x + c));
  std::nth_element(grey.begin(), grey.begin() + grey.size() / 2, grey.end());
  const double target_grey = grey[grey.size() / 2];
  const Eigen::Vector2d centre_left =
      CoverageCentroid(0, window, mask, core, target_grey).value_or(blobs[blob].centroid_px());
  centre_left_px = centre_left;

  // The right eye: find the target by correlating the left patch's
  // difference from its background with the right eye's, along the
  // epipolar rows. Differences, not grey values: the patch's rim shows the
  // scene behind the target, which lies at another disparity and would pull
  // the match. Then the same coverage centroid there, so that both centres
  // come from one estimator.
  const int half = std::min((extent_px + 1) / 2 + 2, 32);
  const int tu = static_cast<int>(std::lround(centre_left.x()));
  const int tv = static_cast<int>(std::lround(centre_left.y()));
  const cv::Rect patch(tu - half, tv - half, 2 * half + 1, 2 * half + 1);
  if ((patch & image_rect) != patch) return false;
  const int slack = config.epipolar_slack_px;
  const cv::Rect search = cv::Rect(patch.x - max_disparity_px, patch.y - slack,
                                   patch.width + max_disparity_px + 1, patch.height + 2 * slack) &
                          image_rect;
  if (search.width < patch.width || search.height < patch.height) return false;
  cv::Mat templ, scene;
  left_rect(patch).convertTo(templ, CV_32F);
  templ -= background[0](patch);
  right_rect(search).convertTo(scene, CV_32F);
  scene -= background[1](search);
  cv::matchTemplate(scene, templ, ncc, cv::TM_CCOEFF_NORMED);
  double best = 0.0;
  cv::Point at;
  cv::minMaxLoc(ncc, nullptr, &best, nullptr, &at);
  if (!(best >= config.ncc_min)) return false;
  const cv::Rect right_window = window + (search.tl() + at - patch.tl());
  if ((right_window & image_rect) != right_window) return false;
  cv::Mat right_mask;
  cv::dilate(mask, right_mask, cv::Mat());  // the match is whole pixels: one more of rim
  const std::optional<Eigen::Vector2d> centre_right =
      CoverageCentroid(1, right_window, right_mask, core, target_grey);
  if (!centre_right) return false;

  const double side_px = std::min(std::max(config.min_roi_side_px, config.roi_margin * extent_px),
                                  static_cast<double>(std::max(width_px, height_px)));
  obs.detected = true;
  obs.centre_left_px = centre_left.cast<float>();
  obs.centre_right_px = centre_right->cast<float>();
  obs.side_left_px = static_cast<float>(side_px);
  obs.side_right_px = static_cast<float>(side_px);
  Crop(left_rect, centre_left.x(), centre_left.y(), side_px, obs.crop_left);
  Crop(right_rect, centre_right->x(), centre_right->y(), side_px, obs.crop_right);
  obs.bearing_left_w = BearingW(Eye::kLeft, centre_left);
  obs.bearing_right_w = BearingW(Eye::kRight, *centre_right);
  return true;
}

CameraPreprocessor::CameraPreprocessor(const sensors::FisheyeStereoConfig& camera,
                                       const PreprocessConfig& config)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.camera = camera;
  m.config = config.camera;
  m.raw = config.CameraRaw();
  m.max_observations = config.max_observations;
  m.width_px = m.config.rectified_width_px;
  m.height_px = m.config.rectified_height_px;
  // Near the centre Mei's projection maps angle theta to about
  // fx theta / (1 + xi) pixels: the default keeps that scale.
  m.focal_px =
      m.config.rectified_focal_px ? *m.config.rectified_focal_px : camera.fx_px / (1.0 + camera.xi);
  m.principal_px = Eigen::Vector2d(0.5 * (m.width_px - 1), 0.5 * (m.height_px - 1));
  m.X_WC[0] = camera.pose.ToIsometry();
  m.X_WC[0].linear() = m.X_WC[0].linear() * sensors::R_BC();
  m.X_WC[1] = m.X_WC[0] * Eigen::Translation3d(camera.baseline_m, 0.0, 0.0);
  m.BuildMaps();
  const int k = m.config.morphology_kernel_px;
  m.closing_kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k));
  // The right eye is baseline_m along +x_C: a point at depth Z appears
  // f b / Z pixels further left there. Disparities from -1 px (rounding) to
  // that of the nearest range of interest.
  m.max_disparity_px =
      static_cast<int>(std::ceil(m.focal_px * camera.baseline_m / m.config.stereo_min_range_m)) + 1;
  // dilate() takes the maximum of src(x + k - anchor) over the kernel: a
  // left pixel at u marks u - max_disparity_px - 1 ... u + 2 (one pixel of
  // rim either side) and the slack rows.
  const int slack = m.config.epipolar_slack_px;
  m.right_spread_kernel = cv::Mat::ones(2 * slack + 3, m.max_disparity_px + 4, CV_8U);
  m.right_spread_anchor = cv::Point(2, slack + 1);
  m.ResetTracking();
}

CameraPreprocessor::~CameraPreprocessor() = default;
CameraPreprocessor::CameraPreprocessor(CameraPreprocessor&&) noexcept = default;
CameraPreprocessor& CameraPreprocessor::operator=(CameraPreprocessor&&) noexcept = default;

CameraObservation CameraPreprocessor::Process(const sensors::StereoFrame& frame,
                                              std::vector<CameraObservation>* further) {
  CheckSize(frame.left, impl_->camera, "left");
  CheckSize(frame.right, impl_->camera, "right");
  if (further) further->clear();
  return impl_->raw ? impl_->ProcessRaw(frame)
                    : impl_->ProcessRoi(frame, impl_->max_observations > 1 ? further : nullptr);
}

void CameraPreprocessor::Reset() { impl_->ResetTracking(); }

int CameraPreprocessor::rectified_width_px() const { return impl_->width_px; }
int CameraPreprocessor::rectified_height_px() const { return impl_->height_px; }
double CameraPreprocessor::rectified_focal_px() const { return impl_->focal_px; }
Eigen::Vector2d CameraPreprocessor::rectified_principal_px() const { return impl_->principal_px; }
const Eigen::Isometry3d& CameraPreprocessor::X_WC(Eye eye) const {
  return impl_->X_WC[static_cast<int>(eye)];
}

sensors::GrayImage CameraPreprocessor::Rectify(const sensors::GrayImage& fisheye) const {
  CheckSize(fisheye, impl_->camera, "fisheye");
  sensors::GrayImage out;
  out.width = impl_->width_px;
  out.height = impl_->height_px;
  out.pixels.resize(static_cast<std::size_t>(out.width) * out.height);
  cv::Mat dst(out.height, out.width, CV_8UC1, out.pixels.data());
  cv::remap(View(fisheye), dst, impl_->map_fixed_xy, impl_->map_fixed_frac, cv::INTER_LINEAR,
            cv::BORDER_CONSTANT, cv::Scalar(0));
  return out;
}

Eigen::Vector2d CameraPreprocessor::FisheyePixelOf(int u_px, int v_px) const {
  return {impl_->map_x.at<float>(v_px, u_px), impl_->map_y.at<float>(v_px, u_px)};
}

}  // namespace uavsim::pipeline
