#include "apps/bench/bench_raycast.h"

#include <tbb/global_control.h>

#include <functional>
#include <iomanip>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "apps/bench/gbench.h"
#include "sensors/fisheye_stereo.h"
#include "sensors/lidar.h"
#include "sim/world_model.h"

namespace uavsim::sim {
namespace {

constexpr double kMinTimeS = 0.5;

// Google Benchmark times `body`, one call an iteration, for at least
// kMinTimeS of wall time (its first, discarded runs warm caches and lazy
// initialisation). Counter "rays": `rays` per call, per wall second.
gbench::Measurement Time(const std::string& name, double rays, const std::function<void()>& body) {
  gbench::Register(name,
                   [&](benchmark::State& state) {
                     for (auto _ : state) body();
                     state.counters["rays"] =
                         benchmark::Counter(rays, benchmark::Counter::kIsIterationInvariantRate);
                   })
      ->Unit(benchmark::kMillisecond)
      ->MinTime(kMinTimeS);
  return gbench::RunSingle().Fastest();
}

void Row(std::ostream& out, const std::string& what, double rays_per_s, const std::string& note) {
  out << std::left << std::setw(46) << what << std::right << std::fixed << std::setprecision(2)
      << std::setw(10) << rays_per_s * 1e-6 << "  " << note << std::defaultfloat << "\n"
      << std::flush;
}

std::string Ratio(const char* label, double x) {
  std::ostringstream s;
  s << label << " " << std::fixed << std::setprecision(2) << x;
  return s.str();
}

// Single-thread figures: camera rays raw vs packets vs the full Capture,
// LiDAR rays raw vs the full sweep. (tbb's global_control takes the smallest
// active limit, so this one must end before a 2-thread measurement.)
void SingleThreadRays(std::ostream& out, WorldModel& world, sensors::FisheyeStereo& camera,
                      sensors::Lidar& lidar, const Scenario& s, double t_s) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const std::vector<sensors::Ray> cam_rays = camera.WorldRays(sensors::FisheyeStereo::Eye::kLeft);
  const double cam_n = static_cast<double>(cam_rays.size());
  std::vector<sensors::RayHit> hits(cam_rays.size());
  const double raw_cam = Time("camera rtcIntersect1", cam_n, [&] {
                           for (std::size_t i = 0; i < cam_rays.size(); ++i)
                             hits[i] = world.scene().Intersect(cam_rays[i]);
                         }).Counter("rays");
  Row(out, "camera rays, rtcIntersect1 (1 thread)", raw_cam, "raw");
  const double packets =
      Time("camera rtcIntersect8", cam_n, [&] {
        world.scene().IntersectMany(cam_rays.data(), hits.data(), cam_rays.size());
      }).Counter("rays");
  Row(out, "camera rays, rtcIntersect8 packets (1 thread)", packets,
      Ratio("speed-up", packets / raw_cam));
  camera.set_max_threads(1);
  core::RngStream noise(1, "bench/camera");
  camera.set_static_cache(false);
  const double frame_rays = static_cast<double>(camera.rays_per_frame());
  const gbench::Measurement capture =
      Time("camera Capture", frame_rays, [&] { camera.Capture(t_s, s.weather, noise); });
  const double cam_rate = capture.Counter("rays");
  Row(out, "camera Capture, shaded (1 thread)", cam_rate, Ratio("of raw", cam_rate / raw_cam));
  // With the static-scene cache: pixels per second as if every pixel were
  // cast (the same images), and the rays it really casts a frame.
  camera.set_static_cache(true);
  camera.Capture(t_s, s.weather, noise);  // builds the cache
  const gbench::Measurement cached =
      Time("camera Capture, cached", frame_rays, [&] { camera.Capture(t_s, s.weather, noise); });
  std::ostringstream cached_note;
  cached_note << Ratio("speed-up", capture.real_s_per_iteration / cached.real_s_per_iteration)
              << ", " << camera.last_capture_rays() << " of " << camera.rays_per_frame()
              << " rays cast";
  Row(out, "camera Capture, static cache (1 thread)", cached.Counter("rays"), cached_note.str());

  const std::vector<sensors::LidarBeam> beams = lidar.Beams(t_s);
  const double beam_n = static_cast<double>(beams.size());
  std::vector<sensors::RayHit> lhits(beams.size());
  const double raw_lidar = Time("LiDAR rtcIntersect1", beam_n, [&] {
                             for (std::size_t i = 0; i < beams.size(); ++i)
                               lhits[i] = world.scene().Intersect(beams[i].ray);
                           }).Counter("rays");
  Row(out, "LiDAR rays, rtcIntersect1 (1 thread)", raw_lidar, "raw");
  core::RngStream lnoise(1, "bench/lidar");
  const double lidar_rate =
      Time("LiDAR Capture", static_cast<double>(lidar.beams_per_frame()), [&] {
        lidar.Capture(t_s, s.weather, lnoise);
      }).Counter("rays");
  Row(out, "LiDAR Capture, with time slices (1 thread)", lidar_rate,
      Ratio("of raw", lidar_rate / raw_lidar));
}

// One simulated second of the default camera + LiDAR load, on 1 and 2 threads.
void DefaultLoad(std::ostream& out, WorldModel& world, sensors::FisheyeStereo& camera,
                 sensors::Lidar& lidar, const Scenario& s, double t_s, double cam_hz,
                 double lidar_hz) {
  core::RngStream noise(1, "bench/camera"), lnoise(1, "bench/lidar");
  const double beams = static_cast<double>(lidar.Beams(t_s).size());
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    camera.set_max_threads(threads);
    const std::string suffix = ", " + std::to_string(threads) + " threads";
    const double camera_s = Time("camera Capture" + suffix, camera.rays_per_frame(), [&] {
                              world.scene().SetTime(t_s);
                              camera.Capture(t_s, s.weather, noise);
                            }).real_s_per_iteration;
    const double lidar_s = Time("LiDAR Capture" + suffix, beams, [&] {
                             lidar.Capture(t_s, s.weather, lnoise);
                           }).real_s_per_iteration;
    const double second_s = cam_hz * camera_s + lidar_hz * lidar_s;
    std::ostringstream note;
    note << std::fixed << std::setprecision(2) << "real-time factor " << 1.0 / second_s << " with "
         << threads << " thread" << (threads > 1 ? "s" : "");
    Row(out, "camera + LiDAR, default rates",
        (cam_hz * camera.rays_per_frame() + lidar_hz * beams) / second_s, note.str());
  }
}

}  // namespace

int BenchRaycast(bool quiet, std::ostream& out) {
  const Scenario s;  // the default scenario
  WorldModel world(s);
  const double t_s = 10.0;
  world.scene().SetTime(t_s);
  const NodeConfig* cam_node = nullptr;
  const NodeConfig* lidar_node = nullptr;
  for (const auto& n : s.nodes) {
    if (n.sensor.type == sensors::SensorType::kFisheyeStereo && !cam_node) cam_node = &n;
    if (n.sensor.type == sensors::SensorType::kLidar && !lidar_node) lidar_node = &n;
  }
  sensors::FisheyeStereo camera(cam_node->sensor.fisheye, world.scene());
  sensors::Lidar lidar(lidar_node->sensor.lidar, world.scene());

  if (!quiet)
    out << "default city: " << world.scene().static_triangle_count() << " static triangles, "
        << world.scene().moving_object_count() << " moving objects; camera "
        << cam_node->sensor.fisheye.width_px << "x" << cam_node->sensor.fisheye.height_px
        << " stereo, LiDAR " << lidar.beams_per_frame() << " beams per sweep\n";
  out << std::left << std::setw(46) << "measure" << std::right << std::setw(10) << "Mrays/s"
      << "  note\n";
  SingleThreadRays(out, world, camera, lidar, s, t_s);
  DefaultLoad(out, world, camera, lidar, s, t_s, cam_node->sensor.timing().rate_hz,
              lidar_node->sensor.timing().rate_hz);
  return 0;
}

}  // namespace uavsim::sim
