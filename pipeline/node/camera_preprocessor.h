// The camera sensing node's pre-processing (paper Sec. IV-A, "fisheye
// distortion correction with ROI extraction"), without a detector network:
//
//   rectify   each eye to a pinhole view K_new = [f 0 cx; 0 f cy; 0 0 1]
//             (f = camera.rectified_focal_px, or fx_px / (1 + xi) if unset;
//             (cx, cy) the centre of the rectified image) with the eye's own
//             orientation, by cv::omnidir::initUndistortRectifyMap
//             (RECTIFY_PERSPECTIVE), maps computed once. The eyes differ by a
//             translation along x_C only, so the rectified pair is row-aligned.
//             This is the paper's inverse chain (Sec. IV-A, eqs. (5)-(8)), which
//             prints the Mei model with typos; implemented here is Mei 2007 as
//             cv::omnidir implements it (DESIGN.md).
//             A non-zero k3 (our extension, unknown to cv::omnidir) is mapped
//             by the same formula with the k3 r^6 term (fisheye_model.h).
//   detect    OpenCV MOG2 background subtraction on the rectified left eye,
//             a closing, 8-connected blobs; the largest blob of at least
//             min_blob_area_px, preferring those within gate_px of the
//             previous detection. Nothing is detected during the first
//             warmup_frames frames (MOG2 is learning the background).
//   locate    each eye's centre to sub-pixel precision: the centroid of the
//             fraction of each pixel the target covers, a = (I - B) / (T - B),
//             over the blob and a one-pixel rim, with B a running mean of the
//             eye's rectified frames (foreground pixels excluded) and T the
//             target's median grey level. The right eye's blob is found by
//             normalised cross-correlation (TM_CCOEFF_NORMED) of the left
//             patch's I - B with the right eye's along the same rows
//             (+- epipolar_slack_px), over disparities from -1 px to
//             f * baseline / stereo_min_range_m + 1 px; a best score below
//             ncc_min (a blob without a stereo partner, e.g. sensor noise) is
//             no detection.
//   crop      a square ROI of side max(min_roi_side_px, roi_margin * blob
//             extent) centred on each eye's centre (zero outside the image),
//             resampled to kCropPx x kCropPx grey values in [0, 1].
//   bearings  the ROI centre unprojected through K_new into the eye's
//             optical frame and rotated into the world (eq. (4) inverted).
//   raw       (config.CameraRaw()) each whole fisheye image downsampled
//             (area averaging) to kCropPx x kCropPx, detected = true, centres
//             the raw image centre ((w - 1) / 2, (h - 1) / 2), sides the raw
//             width, bearings the optical axes.
//
// Frames: the camera pose is the body frame B (REP 103); each eye's optical
// frame C has x_C = -y_B, y_C = -z_B, z_C = x_B; the right eye sits
// baseline_m along +x_C (sensors/fisheye_stereo.h). Pixel coordinates follow
// OpenCV ((0, 0) the centre of the top-left pixel).
//
// A detection needs both eyes: no blob, a patch that leaves the left image,
// or a best correlation below ncc_min gives detected = false, zero crops,
// zero centres and sides, and the optical axes as bearings (the eye
// positions are always filled). The observation's t_s is the frame's
// t_capture_s.
//
// State: the MOG2 model, the running means and the last detection (hence
// Process is not const).
// Deterministic: the output is a pure function of the frames seen since
// construction (or Reset), whatever OpenCV's thread count. Process throws
// std::invalid_argument if an eye's size differs from the camera config's.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "pipeline/node/observations.h"
#include "pipeline/node/preprocess_config.h"
#include "sensors/fisheye_stereo_config.h"
#include "sensors/frames.h"

namespace uavsim::pipeline {

class CameraPreprocessor {
 public:
  enum class Eye { kLeft = 0, kRight = 1 };

  // Computes the rectification maps (a few ms at 640 x 480).
  CameraPreprocessor(const sensors::FisheyeStereoConfig& camera, const PreprocessConfig& config);
  ~CameraPreprocessor();
  CameraPreprocessor(CameraPreprocessor&&) noexcept;
  CameraPreprocessor& operator=(CameraPreprocessor&&) noexcept;

  // The observation; with `further` (cleared first) and max_observations
  // > 1, up to max_observations - 1 further moving blobs that pass the
  // stereo check, largest first, each located and cropped as the selected
  // one is (the gate follows the selected one only).
  CameraObservation Process(const sensors::StereoFrame& frame,
                            std::vector<CameraObservation>* further = nullptr);

  // Forgets the background model and the last detection.
  void Reset();

  // The rectified pinhole view shared by both eyes.
  int rectified_width_px() const;
  int rectified_height_px() const;
  double rectified_focal_px() const;
  Eigen::Vector2d rectified_principal_px() const;
  // Pose of an eye's optical frame (and its rectified view) in the world.
  const Eigen::Isometry3d& X_WC(Eye eye) const;

  // One eye's image rectified (8-bit, rectified size, bilinear; 0 where the
  // view leaves the fisheye image). Throws std::invalid_argument on a size
  // mismatch.
  sensors::GrayImage Rectify(const sensors::GrayImage& fisheye) const;
  // The fisheye pixel that rectified pixel (u_px, v_px) samples: the
  // rectification map itself (u_px, v_px inside the rectified image).
  Eigen::Vector2d FisheyePixelOf(int u_px, int v_px) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::pipeline
