// What a sensing node's pre-processing hands to its encoder (and to the EKF
// baseline), as plain data: no LibTorch, no OpenCV. World frame ENU, metres.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "core/modality.h"

namespace uavsim::pipeline {

using core::kModalityCount;
using core::Modality;
using core::ModalityName;

// The camera node's ROI around the moving target in both rectified eyes
// (paper Sec. IV-A), plus the geometry a crop alone loses.
struct CameraObservation {
  static constexpr int kCropPx = 128;  // paper: image input 128 x 128
  double t_s = 0.0;
  bool detected = false;         // false: no moving blob; crops are zero
  std::vector<float> crop_left;  // kCropPx * kCropPx grey values in [0, 1], row-major
  std::vector<float> crop_right;
  Eigen::Vector2f centre_left_px = Eigen::Vector2f::Zero();  // ROI centre, rectified left image
  Eigen::Vector2f centre_right_px = Eigen::Vector2f::Zero();
  float side_left_px = 0.0f;  // ROI side before resampling to kCropPx, rectified pixels
  float side_right_px = 0.0f;
  // Unit rays from each eye's centre through its ROI centre, and the eyes'
  // positions: what stereo triangulation needs.
  Eigen::Vector3d eye_left_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d eye_right_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d bearing_left_w = Eigen::Vector3d::UnitX();
  Eigen::Vector3d bearing_right_w = Eigen::Vector3d::UnitX();
};

// A point cloud after pre-processing: LiDAR's dynamic points (channels 4:
// x, y, z, intensity) or radar's largest clusters (channels 5: x, y, z,
// radial velocity m/s, SNR dB). At most kMaxPoints points.
struct PointObservation {
  static constexpr int kMaxPoints = 1024;  // paper: up to 1024 points
  double t_s = 0.0;
  int channels = 4;
  std::vector<float> values;  // count() * channels, row-major
  Eigen::Vector3d sensor_position_w = Eigen::Vector3d::Zero();
  std::size_t count() const {
    return channels > 0 ? values.size() / static_cast<std::size_t>(channels) : 0;
  }
};

}  // namespace uavsim::pipeline
