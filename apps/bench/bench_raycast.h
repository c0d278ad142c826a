// `uavsim bench raycast`: ray-casting throughput in the default city.
#pragma once

#include <ostream>

namespace uavsim::sim {

// In the default scenario's world (city, UAV), on the default camera's and
// LiDAR's own rays:
//  - raw Embree rtcIntersect1 (RaycastScene::Intersect), one thread;
//  - the camera's packets (IntersectMany) on the same rays: the speed-up;
//  - each sensor's achieved rays per second in Capture (shading, noise,
//    weather, point generation included), 1 thread, and its ratio to raw;
//  - the real-time factor of the default camera + LiDAR load (30 stereo
//    frames and 10 sweeps per simulated second) with 1 and 2 threads.
// Google Benchmark times each call (a ray batch, a frame, a sweep) by wall
// clock for at least 0.5 s. Writes a table to `out`: measure, million rays
// per second, and a note (speed-up, ratio to raw, real-time factor); unless
// `quiet`, a description line of the world and sensors first. Returns 0.
int BenchRaycast(bool quiet, std::ostream& out);

}  // namespace uavsim::sim
