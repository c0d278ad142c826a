// `uavsim bench pipeline`: time of the learned pipeline per frame at the
// sensing node and per window at the edge.
#pragma once

#include <ostream>

namespace uavsim::sim {

// LibTorch on one thread (pipeline::InitTorch(1, seed)), untrained weights
// drawn from a fixed seed (timing does not depend on the weights' values), and
// fixed-seed synthetic inputs from core::RngStream. Cases:
//   node encode (NodeEncoder::Encode, z = 16, IB head):
//     camera  two 128 x 128 crops in [0, 1] plus the ROI geometry
//     lidar   1024 and 128 points (x y z intensity)
//     radar   64 points (x y z velocity snr)
//   edge window (EdgeLocalizer::OnWindow: TE-Align, MADW, MICA, Mamba, head;
//     z = 16, t^w = 0.2 s) fed the latents the default scenario's sensors send
//     in one window: 6 camera (30 Hz), 2 LiDAR (10 Hz), 3 radar (15 Hz)
// Google Benchmark runs each case for a warm-up of 0.1 s, then times each
// call as a repetition of one iteration, max(100, 1 s / mean call time) of
// them, so every call's wall time is taken. One table row per case: calls
// timed, median, mean and 95th percentile wall ms per call, mean thread CPU
// ms per call, calls per second (1000 / mean), the target (issue: encode
// <= 5 ms per frame on one core; edge <= 1 ms per window) and the paper's
// Raspberry Pi 5 figure (camera 0.02 s, point cloud 0.09 s, for its whole
// node pipeline: pre-processing and encoder). With `quiet` only the table is
// written. Returns 0.
int BenchPipeline(bool quiet, std::ostream& out);

}  // namespace uavsim::sim
