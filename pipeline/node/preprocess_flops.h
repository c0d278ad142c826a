// Table III of the paper, pre-processing columns: ESTIMATES of the
// operations one frame's pre-processing costs, from the algorithms'
// operation counts at stated sizes. The pre-processing is OpenCV, FFTW,
// hash tables and DBSCAN, not a network whose layers could be walked
// (encoder_flops.h), so each stage is "operations per item x items" with
// the per-item count read from what the code (and, for OpenCV's MOG2 and
// morphology, our reading of OpenCV's algorithm) does per pixel, point or
// transform. One operation is one add, multiply, divide, compare or floor,
// integer or float (most camera stages work on 8-bit pixels); memory
// traffic, branches and hash-table probing beyond its key arithmetic are
// not counted. A complex FFT of N points counts 5 N log2 N (the usual
// radix-2 figure FFTW's benchmarks use). Counts that depend on the scene
// (blob size, points outside the static background, detections) take the
// value the caller gives, and each stage's text states it.
//
// What is estimated is what uavsim runs (camera_preprocessor.h,
// lidar_preprocessor.h, radar_preprocessor.h and, for the radar's point
// cloud, sensors/radar_processor.h, which the paper counts as the radar's
// pre-processing: Sec. IV-A "point-cloud construction and target
// clustering"). The camera's rectification maps are computed once at
// start, not per frame, and are not counted; the raw (ablation) variants
// are not estimated.
#pragma once

#include <string>
#include <vector>

#include "pipeline/node/preprocess_config.h"
#include "sensors/fisheye_stereo_config.h"
#include "sensors/fmcw_radar_config.h"

namespace uavsim::pipeline {

struct OpStage {
  std::string stage;  // what runs, and how ops_per_item is made up
  double ops_per_item = 0.0;
  double items = 0.0;
  std::string items_text;  // how `items` is made up, e.g. "2 eyes x 640 x 480 px"
  double Ops() const { return ops_per_item * items; }
};

struct OpEstimate {
  std::vector<OpStage> stages;
  double Ops() const;
};

// The ROI path of CameraPreprocessor on one stereo frame: rectification of
// both eyes at config.rectified_{width,height}_px, MOG2 with OpenCV's
// default 5 Gaussian modes a pixel (each pixel counted with all 5, an upper
// bound), closing, labelling, the two running means, and, for a target
// blob of `blob_extent_px`, the stereo match, the centroids and the two
// 128 x 128 crops.
OpEstimate EstimateCameraPreprocessOps(const sensors::FisheyeStereoConfig& camera,
                                       const CameraPreprocessConfig& config,
                                       int blob_extent_px = 8);

// LidarPreprocessor after warm-up on a scan of `points_per_scan` returns:
// each point's voxel and one static-voxel probe; with static_neighbourhood,
// 26 more probes for every point (an upper bound: only points outside a
// static voxel make them); DBSCAN of `dynamic_points` points.
OpEstimate EstimateLidarPreprocessOps(double points_per_scan, const LidarPreprocessConfig& config,
                                      double dynamic_points = 16.0);

// The radar's point-cloud construction (RadarProcessor: windows, range and
// Doppler FFTs, clutter removal, power map, CA-CFAR, MUSIC per detection)
// and RadarPreprocessor's DBSCAN, for `detections` CFAR detections.
OpEstimate EstimateRadarPreprocessOps(const sensors::FmcwRadarConfig& radar,
                                      const RadarPreprocessConfig& config, int detections = 1);

}  // namespace uavsim::pipeline
