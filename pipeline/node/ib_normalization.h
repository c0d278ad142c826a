// World-frame observations -> IB-CC network inputs and targets (paper
// Sec. IV-B), torch-free so the node, the trainer and tests share one
// definition. Every network quantity is dimensionless and of order one:
//
//   position      p_n = (p_w - centre_m) / scale_m          (inputs and target)
//   LiDAR         intensity_n = intensity / intensity_scale
//   radar         v_n = v_mps / velocity_scale_mps,
//                 snr_n = (snr_db - snr_offset_db) / snr_scale_db
//   camera ROI    centre_n = (c_px - size_px / 2) / (size_px / 2)  per axis, in [-1, 1]
//                 side_n = side_px / image_width_px
//                 bearings: the world unit rays as they are
//
// The normalisation is part of a trained model (saved in its JSON sidecar): a
// model only understands inputs normalised the way it was trained.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "pipeline/node/observations.h"

namespace uavsim::pipeline {

struct IbNormalization {
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();  // scene centre, world ENU
  double scale_m = 50.0;                               // metres per unit
  // Size of the rectified image the camera ROI geometry refers to.
  double image_width_px = 640.0;
  double image_height_px = 480.0;
  double intensity_scale = 1.0;      // LiDAR intensity is already in [0, 1]
  double velocity_scale_mps = 10.0;  // about a small UAV's top speed
  double snr_offset_db = 15.0;       // typical CFAR detection SNR ...
  double snr_scale_db = 10.0;        // ... and its spread
};

template <class V>
void Visit(V& v, IbNormalization& c);

// Centre = mean of `positions_w`, scale = the largest per-axis standard
// deviation (at least 1 m), other fields kept from `base`. For the trainer:
// fit on the training split's truth. Throws std::invalid_argument if empty.
IbNormalization FitPositionNormalization(const std::vector<Eigen::Vector3d>& positions_w,
                                         const IbNormalization& base = {});

Eigen::Vector3d NormalizePosition(const Eigen::Vector3d& p_w, const IbNormalization& n);
Eigen::Vector3d DenormalizePosition(const Eigen::Vector3d& p_n, const IbNormalization& n);

// Number of ROI geometry features appended to the camera's h^c.
constexpr int kCameraGeometryFeatures = 18;

// The camera ROI geometry a crop alone loses, in this order: left centre
// (x, y), right centre (x, y), left side, right side, left bearing (3), right
// bearing (3), left eye position (3, normalised like a point), right eye (3).
std::vector<float> CameraGeometryFeatures(const CameraObservation& obs, const IbNormalization& n);

// Input channels of the PointNet encoder per point modality: 4 for LiDAR
// (x y z intensity), 5 for radar (x y z radial-velocity snr). Throws
// std::invalid_argument for the camera.
int PointChannels(Modality m);

// Writes the normalised points channel-major into `out` (channels x count,
// i.e. Conv1d layout; out[c * count + i]). Throws std::invalid_argument if
// the observation has the wrong channel count for `m`, more than
// PointObservation::kMaxPoints points, a value array that is not a whole
// number of points, or a NaN or infinite value.
void NormalizePoints(const PointObservation& obs, Modality m, const IbNormalization& n, float* out);

}  // namespace uavsim::pipeline
