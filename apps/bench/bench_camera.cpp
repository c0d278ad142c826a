#include "apps/bench/bench_camera.h"

#include <tbb/global_control.h>

#include <cmath>
#include <functional>
#include <iomanip>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/background_segm.hpp>
#include <string>
#include <vector>

#include "apps/bench/gbench.h"
#include "pipeline/node/camera_preprocessor.h"
#include "sensors/fisheye_stereo.h"
#include "sim/world_model.h"

namespace uavsim::sim {
namespace {

constexpr double kMinTimeS = 0.5;
constexpr double kWarmupS = 10.0;  // frames before the timed second: MOG2 learnt, detection on
constexpr int kTimedFrames = 30;

// Milliseconds per call of `body` (wall clock; the fastest of three repetitions).
double TimeMs(const std::string& name, const std::function<void()>& body) {
  gbench::Register(name,
                   [&](benchmark::State& state) {
                     for (auto _ : state) body();
                   })
      ->Unit(benchmark::kMillisecond)
      ->MinTime(kMinTimeS)
      ->Repetitions(3)
      ->ReportAggregatesOnly(false);
  return gbench::RunSingle().Fastest().real_s_per_iteration * 1e3;
}

void Row(std::ostream& out, const std::string& part, double ms, double of_ms, const char* of) {
  out << std::left << std::setw(52) << part << std::right << std::fixed << std::setprecision(3)
      << std::setw(9) << ms << "  ";
  if (of_ms > 0.0)
    out << std::setprecision(0) << std::setw(3) << 100.0 * ms / of_ms << " % of " << of;
  out << std::defaultfloat << "\n" << std::flush;
}

cv::Mat View(const sensors::GrayImage& image) {
  return cv::Mat(image.height, image.width, CV_8UC1,
                 const_cast<std::uint8_t*>(image.pixels.data()));
}

// The stereo frames of the flight at the camera's rate, from t = 0 s.
std::vector<sensors::StereoFrame> Frames(WorldModel& world, const sensors::FisheyeStereo& camera,
                                         const Scenario& s, double rate_hz, int count) {
  core::RngStream noise(1, "bench/camera");
  std::vector<sensors::StereoFrame> frames;
  for (int k = 0; k < count; ++k) {
    const double t_s = k / rate_hz;
    world.scene().SetTime(t_s);
    frames.push_back(camera.Capture(t_s, s.weather, noise));
  }
  return frames;
}

void CaptureRows(std::ostream& out, WorldModel& world, const sensors::FisheyeStereoConfig& config,
                 const Scenario& s) {
  sensors::FisheyeStereo camera(config, world.scene());
  sensors::FisheyeStereoConfig quiet_config = config;
  quiet_config.sensor_noise = false;
  sensors::FisheyeStereo noiseless(quiet_config, world.scene());
  for (sensors::FisheyeStereo* c : {&camera, &noiseless}) {
    c->set_max_threads(1);
    c->set_small_objects([&world](double t_s) { return world.SmallObjects(t_s); });
  }
  const double t_s = kWarmupS;
  world.scene().SetTime(t_s);
  core::RngStream noise(1, "bench/camera");
  const double cached = TimeMs("Capture, cached", [&] { camera.Capture(t_s, s.weather, noise); });
  const double quiet =
      TimeMs("Capture, cached, no noise", [&] { noiseless.Capture(t_s, s.weather, noise); });
  camera.set_static_cache(false);
  const double full = TimeMs("Capture, no cache", [&] { camera.Capture(t_s, s.weather, noise); });
  Row(out, "Capture (static cache: the run's path)", cached, 0.0, "");
  Row(out, "  of which sensor noise (Capture without it: the rest)", cached - quiet, cached,
      "Capture");
  Row(out, "Capture without the static cache", full, 0.0, "");
}

// The pre-processing's steps alone, as camera_preprocessor.cpp calls them.
struct Steps {
  cv::Mat map_xy, map_frac, closing, spread;
  cv::Point spread_anchor;
  cv::Ptr<cv::BackgroundSubtractorMOG2> mog2;
  std::vector<cv::Mat> left, right, foreground;  // rectified frames and their masks

  Steps(const pipeline::CameraPreprocessor& p, const sensors::FisheyeStereoConfig& camera,
        const pipeline::CameraPreprocessConfig& c) {
    const int w = p.rectified_width_px(), h = p.rectified_height_px();
    cv::Mat map_x(h, w, CV_32FC1), map_y(h, w, CV_32FC1);
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) {
        const Eigen::Vector2d at = p.FisheyePixelOf(u, v);
        map_x.at<float>(v, u) = static_cast<float>(at.x());
        map_y.at<float>(v, u) = static_cast<float>(at.y());
      }
    cv::convertMaps(map_x, map_y, map_xy, map_frac, CV_16SC2);
    const int k = c.morphology_kernel_px;
    closing = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k));
    const int max_disparity =
        static_cast<int>(
            std::ceil(p.rectified_focal_px() * camera.baseline_m / c.stereo_min_range_m)) +
        1;
    spread = cv::Mat::ones(2 * c.epipolar_slack_px + 3, max_disparity + 4, CV_8U);
    spread_anchor = cv::Point(2, c.epipolar_slack_px + 1);
    mog2 = cv::createBackgroundSubtractorMOG2(c.mog2_history_frames, c.mog2_var_threshold, false);
  }
  void Rectify(const sensors::StereoFrame& f, cv::Mat& l, cv::Mat& r) const {
    cv::remap(View(f.left), l, map_xy, map_frac, cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
    cv::remap(View(f.right), r, map_xy, map_frac, cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
  }
};

void PreprocessRows(std::ostream& out, const std::vector<sensors::StereoFrame>& frames,
                    const sensors::FisheyeStereoConfig& camera,
                    const pipeline::PreprocessConfig& config) {
  const int warm = static_cast<int>(frames.size()) - kTimedFrames;
  pipeline::CameraPreprocessor pre(camera, config);
  for (int k = 0; k < warm; ++k) pre.Process(frames[k]);
  int i = 0;
  const double process = TimeMs("Process", [&] { pre.Process(frames[warm + i++ % kTimedFrames]); });
  Row(out, "pre-processing: CameraPreprocessor::Process", process, 0.0, "");

  Steps st(pre, camera, config.camera);
  cv::Mat l, r, fg;
  for (int k = 0; k < static_cast<int>(frames.size()); ++k) {
    st.Rectify(frames[k], l, r);
    st.mog2->apply(l, fg);
    if (k < warm) continue;
    st.left.push_back(l.clone());
    st.right.push_back(r.clone());
    cv::morphologyEx(fg, fg, cv::MORPH_CLOSE, st.closing);
    st.foreground.push_back(fg.clone());
  }
  i = 0;
  Row(out, "  rectify both eyes (remap)",
      TimeMs("remap", [&] { st.Rectify(frames[warm + i++ % kTimedFrames], l, r); }), process,
      "Process");
  i = 0;
  Row(out, "  MOG2 on the left eye",
      TimeMs("MOG2", [&] { st.mog2->apply(st.left[i++ % kTimedFrames], fg); }), process, "Process");
  i = 0;
  Row(out, "  closing",
      TimeMs("closing",
             [&] {
               cv::morphologyEx(st.foreground[i++ % kTimedFrames], fg, cv::MORPH_CLOSE, st.closing);
             }),
      process, "Process");
  cv::Mat labels;
  std::vector<cv::Point> points;
  i = 0;
  Row(out, "  labelling (connectedComponents, findNonZero)",
      TimeMs("labels",
             [&] {
               const cv::Mat& f = st.foreground[i++ % kTimedFrames];
               cv::connectedComponents(f, labels, 8, CV_32S);
               cv::findNonZero(f, points);
             }),
      process, "Process");
  cv::Mat background[2], not_learnt, learn;
  st.left[0].convertTo(background[0], CV_32F);
  st.right[0].convertTo(background[1], CV_32F);
  i = 0;
  Row(out, "  running means (dilate, masked accumulateWeighted)",
      TimeMs("means",
             [&] {
               const int k = i++ % kTimedFrames;
               cv::dilate(st.foreground[k], not_learnt, cv::Mat());
               cv::bitwise_not(not_learnt, learn);
               cv::accumulateWeighted(st.left[k], background[0], 1.0 / 300.0, learn);
               cv::dilate(st.foreground[k], not_learnt, st.spread, st.spread_anchor);
               cv::bitwise_not(not_learnt, learn);
               cv::accumulateWeighted(st.right[k], background[1], 1.0 / 300.0, learn);
             }),
      process, "Process");
}

}  // namespace

int BenchCamera(bool quiet, std::ostream& out) {
  const Scenario s;  // the default scenario
  WorldModel world(s);
  const NodeConfig* node = nullptr;
  for (const auto& n : s.nodes)
    if (n.sensor.type == sensors::SensorType::kFisheyeStereo && !node) node = &n;
  const sensors::FisheyeStereoConfig& config = node->sensor.fisheye;
  const double rate_hz = node->sensor.timing().rate_hz;
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const int old_threads = cv::getNumThreads();
  cv::setNumThreads(1);
  if (!quiet)
    out << "default camera node: " << config.width_px << " x " << config.height_px << " stereo at "
        << rate_hz << " Hz, one thread; pre-processing timed on the " << kTimedFrames
        << " frames after " << kWarmupS << " s of flight\n";
  out << std::left << std::setw(52) << "part" << std::right << std::setw(9) << "ms/frame"
      << "  share\n";
  CaptureRows(out, world, config, s);
  sensors::FisheyeStereo camera(config, world.scene());
  camera.set_small_objects([&world](double t_s) { return world.SmallObjects(t_s); });
  const std::vector<sensors::StereoFrame> frames = Frames(
      world, camera, s, rate_hz, static_cast<int>(std::lround(kWarmupS * rate_hz)) + kTimedFrames);
  PreprocessRows(out, frames, config, s.pipeline.preprocess);
  cv::setNumThreads(old_threads);
  return 0;
}

}  // namespace uavsim::sim
