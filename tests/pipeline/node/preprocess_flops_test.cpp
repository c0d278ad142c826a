// The pre-processing operation estimates (preprocess_flops.h): each stage is
// its stated formula at the configured sizes.
#include "pipeline/node/preprocess_flops.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <string>

namespace uavsim::pipeline {
namespace {

const OpStage& Stage(const OpEstimate& e, const std::string& prefix) {
  const auto it = std::find_if(e.stages.begin(), e.stages.end(),
                               [&](const OpStage& s) { return s.stage.rfind(prefix, 0) == 0; });
  INFO("stage " << prefix);
  REQUIRE(it != e.stages.end());
  return *it;
}

TEST_CASE("Pre-processing estimates: the radar's FFTs and the camera's per-pixel stages",
          "[pipeline]") {
  const sensors::FmcwRadarConfig radar;  // 512 samples, 64 chirps, 4 x 3 antennas
  const PreprocessConfig pre;
  const OpEstimate r = EstimateRadarPreprocessOps(radar, pre.radar, 1);
  // 5 N log2 N per complex FFT: 768 range FFTs of 512, 6144 Doppler FFTs of 64.
  CHECK(Stage(r, "range FFTs").Ops() == 5.0 * 512 * 9 * 64 * 12);
  CHECK(Stage(r, "Doppler FFTs").Ops() == 5.0 * 64 * 6 * 512 * 12);
  CHECK(Stage(r, "range window").Ops() == 2.0 * 512 * 64 * 12);
  // MUSIC: a 31 x 15 grid (+-60 and +-30 degrees at 4-degree steps), 9 snapshots.
  CHECK(Stage(r, "angle by MUSIC").stage.find("9 snapshots, 465-point grid") != std::string::npos);
  double sum = 0.0;
  for (const OpStage& s : r.stages) sum += s.ops_per_item * s.items;
  CHECK(r.Ops() == Approx(sum));
  CHECK(EstimateRadarPreprocessOps(radar, pre.radar, 3).Ops() - r.Ops() ==
        Approx(2.0 * Stage(r, "angle by MUSIC").Ops()).epsilon(0.01));

  const sensors::FisheyeStereoConfig camera;  // 640 x 480 rectified by default
  const OpEstimate c = EstimateCameraPreprocessOps(camera, pre.camera);
  CHECK(Stage(c, "rectify").Ops() == 7.0 * 2 * 640 * 480);
  CHECK(Stage(c, "MOG2").Ops() == 36.0 * 640 * 480);
  // Disparities up to ceil(f b / 2 m) + 1 with f = 230 / 2: ceil(6.9) + 1 = 8.
  CHECK(Stage(c, "right running mean (5x12 dilate").ops_per_item == 4 + 11 + 5);

  const OpEstimate l = EstimateLidarPreprocessOps(24000, pre.lidar, 16);
  CHECK(Stage(l, "voxel").Ops() == 30.0 * 24000);
  CHECK(Stage(l, "26 neighbour probes").Ops() == 468.0 * 24000);
  LidarPreprocessConfig no_neighbours = pre.lidar;
  no_neighbours.static_neighbourhood = false;
  no_neighbours.clusters_kept = 0;
  CHECK(EstimateLidarPreprocessOps(24000, no_neighbours).Ops() == 30.0 * 24000);
}

}  // namespace
}  // namespace uavsim::pipeline
