// One eye of the fisheye camera: Mei's unified projection model (C. Mei and
// P. Rives, "Single View Point Omnidirectional Camera Calibration from Planar
// Grids", ICRA 2007) exactly as OpenCV's cv::omnidir implements it, plus a
// sixth-order radial term k3 (our extension; k3 = 0 is OpenCV's model).
//
// Frames and units: points and rays are in the optical frame C (z forward,
// x right, y down), metres; pixel coordinates (u, v) follow OpenCV: (0, 0)
// is the centre of the top-left pixel, u to the right, v down, so pixel
// (i, j) covers [i - 0.5, i + 0.5) x [j - 0.5, j + 0.5).
//
// For X_C = (x, y, z):
//   x_s = X_C / |X_C|                              (onto the unit sphere)
//   m_u = (x_s / (z_s + xi), y_s / (z_s + xi))     (normalised plane)
//   r^2 = |m_u|^2, radial = 1 + k1 r^2 + k2 r^4 + k3 r^6
//   x_d = x_u radial + 2 p1 x_u y_u + p2 (r^2 + 2 x_u^2)
//   y_d = y_u radial + p1 (r^2 + 2 y_u^2) + 2 p2 x_u y_u
//   u = fx x_d + cx, v = fy y_d + cy               (no skew)
// The paper's Sec. IV-A prints this with typos (radial terms in the 3-D
// distance r^c, non-standard tangential terms, a different depth formula);
// this is Mei 2007 / cv::omnidir, as DESIGN.md decides.
//
// Valid domain: the model is one-to-one for z_s > -min(xi, 1/xi) (the
// sphere's points that Mei's lifting returns) and while the distortion's
// Jacobian stays regular (|m_u| below the radius where the lens "folds").
// Outside it Project returns nullopt and Unproject returns the zero vector.
// Pure and thread-safe (all methods const, no shared state).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "sensors/fisheye_stereo_config.h"

namespace uavsim::sensors {

// A unit viewing ray per pixel, through the pixel centres, row-major.
struct RayTable {
  int width_px = 0;
  int height_px = 0;
  std::vector<Eigen::Vector3f> direction_C;  // unit; zero where the pixel sees nothing
  std::vector<std::uint8_t> valid;           // 1 where the pixel sees the world, 0 where not
  std::size_t valid_count = 0;
};

class FisheyeModel {
 public:
  // Reads the intrinsics (width_px ... k3) of `config`; the pose and
  // baseline are the stereo rig's business.
  explicit FisheyeModel(const FisheyeStereoConfig& config);

  // Pixel of the point p_C (any distance > 0), or nullopt if p_C is outside
  // the model's valid domain or lands outside the image.
  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& p_C) const;

  // Unit ray in C that projects to pixel coordinates (u, v): undistortion by
  // fixed-point iteration (as cv::omnidir::undistortPoints) polished by
  // Newton steps, then Mei's closed-form lifting onto the sphere. Returns the
  // zero vector where (u, v) sees nothing (outside the valid domain).
  Eigen::Vector3d Unproject(double u, double v) const;

  // The ray of every pixel centre, computed once.
  RayTable ComputeRayTable() const;

  int width_px() const { return width_px_; }
  int height_px() const { return height_px_; }
  // Largest undistorted radius |m_u| of the valid domain (may be infinite).
  double max_undistorted_radius() const;

 private:
  Eigen::Vector2d Distort(const Eigen::Vector2d& m_u) const;
  Eigen::Matrix2d DistortJacobian(const Eigen::Vector2d& m_u) const;
  double FoldR2(double r_cap) const;
  std::optional<Eigen::Vector2d> Undistort(const Eigen::Vector2d& m_d) const;

  int width_px_, height_px_;
  double xi_, fx_, fy_, cx_, cy_, k1_, k2_, p1_, p2_, k3_;
  double min_z_s_;  // z_s must exceed this
  double max_r2_;   // |m_u|^2 must stay below this
};

}  // namespace uavsim::sensors
