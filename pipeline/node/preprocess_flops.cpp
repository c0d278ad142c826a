#include "pipeline/node/preprocess_flops.h"

#include <algorithm>
#include <cmath>

#include "pipeline/node/observations.h"

namespace uavsim::pipeline {
namespace {

std::string Int(double v) { return std::to_string(std::llround(v)); }

// DBSCAN's neighbour queries on a k-d tree of m points: about log2 m nodes
// plus a handful (8) of candidates each, every test a distance in 3 or 4
// dimensions and a compare (9 operations).
OpStage DbscanStage(double points, const std::string& what) {
  const double per_point = 9.0 * (std::log2(std::max(points, 1.0)) + 8.0);
  return {"DBSCAN of " + what + " (k-d tree: (log2 m + 8) tests of 9)", per_point, points,
          "m = " + Int(points) + " points"};
}

}  // namespace

double OpEstimate::Ops() const {
  double n = 0.0;
  for (const OpStage& s : stages) n += s.Ops();
  return n;
}

OpEstimate EstimateCameraPreprocessOps(const sensors::FisheyeStereoConfig& camera,
                                       const CameraPreprocessConfig& c, int blob_extent_px) {
  const double w = c.rectified_width_px, h = c.rectified_height_px;
  const double pixels = w * h;
  const std::string px = Int(w) + " x " + Int(h) + " px";
  // As CameraPreprocessor sets them up.
  const double focal_px =
      c.rectified_focal_px ? *c.rectified_focal_px : camera.fx_px / (1.0 + camera.xi);
  const int max_disparity_px =
      static_cast<int>(std::ceil(focal_px * camera.baseline_m / c.stereo_min_range_m)) + 1;
  const int slack = c.epipolar_slack_px;
  const int k = c.morphology_kernel_px;
  constexpr int kModes = 5;  // OpenCV's default nmixtures, which we keep

  OpEstimate e;
  e.stages.push_back(
      {"rectify (bilinear remap: 4 mul + 3 add)", 7.0, 2.0 * pixels, "2 eyes x " + px});
  // Per mode: weight decay (2), its share of the normalisation (2); the
  // matched mode: distance and the two threshold tests (6), the update of
  // weight, mean and variance with its clamps and the sort step (10).
  e.stages.push_back({"MOG2, left eye (" + std::to_string(kModes) + " modes: 4 x modes + 16)",
                      4.0 * kModes + 16.0, pixels, px});
  if (k > 1)
    e.stages.push_back({"closing " + std::to_string(k) + "x" + std::to_string(k) +
                            " (dilate + erode, separable: 4 (k - 1))",
                        4.0 * (k - 1), pixels, px});
  e.stages.push_back({"8-connected labelling (4) + foreground scan (1)", 5.0, pixels, px});
  e.stages.push_back({"left running mean (3x3 dilate 4, not 1, masked update 4)", 9.0, pixels, px});
  // The right eye's mask is dilated by a (2s + 3) x (d + 4) rectangle.
  e.stages.push_back({"right running mean (" + std::to_string(2 * slack + 3) + "x" +
                          std::to_string(max_disparity_px + 4) +
                          " dilate, separable, not 1, masked update 4)",
                      (2.0 * slack + 2.0) + (max_disparity_px + 3.0) + 5.0, pixels, px});
  const int half = std::min((blob_extent_px + 1) / 2 + 2, 32);
  const double patch = 2.0 * half + 1.0;
  e.stages.push_back(
      {"stereo NCC of a " + Int(patch) + "x" + Int(patch) + " patch (2 T^2 + 10 a position)",
       2.0 * patch * patch + 10.0, (max_disparity_px + 2.0) * (2.0 * slack + 1.0),
       Int(max_disparity_px + 2) + " disparities x " + std::to_string(2 * slack + 1) +
           " rows (blob " + std::to_string(blob_extent_px) + " px)"});
  const double window = (blob_extent_px + 4.0) * (blob_extent_px + 4.0);
  e.stages.push_back({"sub-pixel centroids (6 a window pixel)", 6.0, 2.0 * window,
                      "2 eyes x " + Int(window) + " px"});
  constexpr double kCrop = CameraObservation::kCropPx;
  e.stages.push_back(
      {"ROI crops (bilinear 7 + scale 1)", 8.0, 2.0 * kCrop * kCrop, "2 eyes x 128 x 128 px"});
  return e;
}

OpEstimate EstimateLidarPreprocessOps(double points_per_scan, const LidarPreprocessConfig& c,
                                      double dynamic_points) {
  const std::string n = Int(points_per_scan) + " returns";
  OpEstimate e;
  // finite checks 3; per axis multiply, floor, two clamps (12); the packed
  // key: per axis offset and two clamps, then two shifts and two ors (13);
  // the probe: bucket and compare (2).
  e.stages.push_back({"voxel, key and static probe (3 + 12 + 13 + 2)", 30.0, points_per_scan, n});
  if (c.static_neighbourhood)
    e.stages.push_back({"26 neighbour probes (offsets 3 + key 13 + probe 2 each)", 26.0 * 18.0,
                        points_per_scan, n + " (upper bound: every point)"});
  if (c.clusters_kept > 0) e.stages.push_back(DbscanStage(dynamic_points, "the dynamic points"));
  return e;
}

OpEstimate EstimateRadarPreprocessOps(const sensors::FmcwRadarConfig& r,
                                      const RadarPreprocessConfig& c, int detections) {
  const sensors::RadarProcessingConfig& p = r.processing;
  const double ns = r.adc_samples, nc = r.chirps_per_frame, m = r.nx * r.ny;
  const double cube = ns * nc * m;
  const std::string cube_text =
      Int(ns) + " samples x " + Int(nc) + " chirps x " + Int(m) + " antennas";
  OpEstimate e;
  e.stages.push_back({"range window (complex x real 2)", 2.0, cube, cube_text});
  e.stages.push_back({"range FFTs (5 N log2 N, N = " + Int(ns) + ")", 5.0 * ns * std::log2(ns),
                      nc * m, Int(nc) + " chirps x " + Int(m) + " antennas"});
  if (p.clutter_removal)
    e.stages.push_back({"clutter removal (weighted mean 4, subtract 2)", 6.0, cube, cube_text});
  e.stages.push_back({"Doppler window (complex x complex 6)", 6.0, cube, cube_text});
  e.stages.push_back({"Doppler FFTs (5 N log2 N, N = " + Int(nc) + ")", 5.0 * nc * std::log2(nc),
                      ns * m, Int(ns) + " range bins x " + Int(m) + " antennas"});
  e.stages.push_back({"power |x|^2 summed over antennas (3 + 1)", 4.0, cube, cube_text});
  // Scaling 1, summed-area table 2, the outer and guard window sums 3 each,
  // their difference, the threshold product and the compare 3.
  e.stages.push_back({"CA-CFAR (scale 1, summed-area table 2, windows 6, test 3)", 12.0, ns * nc,
                      Int(ns) + " x " + Int(nc) + " cells"});
  // MUSIC per detection: covariance of K snapshots (8 K M^2) and its
  // forward-backward average (4 M^2), the Hermitian eigen-decomposition
  // (about 4 x 9 M^3: Golub & Van Loan's 9 n^3 for a real symmetric one with
  // vectors, complex arithmetic 4x), the grid spectrum ||E_s^H a||^2 of one
  // source (8 M + 3 a grid point) and the pattern search (about 18 steps of
  // 8 evaluations, a steering vector 6 M + 30 and the spectrum 8 M + 3).
  const auto axis = [&](double fov_deg, int elements) {
    if (elements < 2) return 1.0;
    return 2.0 * std::floor(std::min(0.5 * fov_deg, 90.0) / p.music_grid_step_deg + 1e-9) + 1.0;
  };
  const double grid = axis(r.fov_azimuth_deg, r.nx) * axis(r.fov_elevation_deg, r.ny);
  const double snapshots = std::pow(2.0 * p.snapshot_neighbourhood_cells + 1.0, 2.0);
  const double music = 8.0 * snapshots * m * m + 4.0 * m * m + 36.0 * m * m * m +
                       grid * (8.0 * m + 3.0) + 18.0 * 8.0 * (14.0 * m + 33.0);
  e.stages.push_back(
      {std::string("angle by MUSIC (") + Int(snapshots) + " snapshots, " + Int(grid) +
           "-point grid, refinement)" +
           (p.angle_method == sensors::AngleMethod::kMusic ? "" : " [configured: not MUSIC]"),
       music, static_cast<double>(detections), std::to_string(detections) + " detection(s)"});
  if (c.clusters_kept > 0) e.stages.push_back(DbscanStage(detections, "the detections"));
  return e;
}

}  // namespace uavsim::pipeline
