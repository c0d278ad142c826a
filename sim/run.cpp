#include "sim/run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <set>

#include "channel/beamformer.h"
#include "channel/edge_receiver.h"
#include "channel/packet.h"
#include "channel/rain_attenuation.h"
#include "channel/uplink.h"
#include "pipeline/anchored/anchors.h"
#include "pipeline/baselines/ekf.h"
#include "pipeline/model_bundle.h"
#include "pipeline/node/camera_preprocessor.h"
#include "pipeline/node/lidar_preprocessor.h"
#include "pipeline/node/radar_preprocessor.h"
#include "pipeline/torch_runtime.h"
#include "results/csv.h"
#include "results/plot.h"
#include "results/run_directory.h"
#include "sensors/fisheye_stereo.h"
#include "sensors/fmcw_radar.h"
#include "sensors/lidar.h"
#include "sensors/radar_processor.h"
#include "sim/core/periodic_process.h"
#include "sim/core/progress.h"
#include "sim/core/rng.h"
#include "sim/core/simulator.h"
#include "sim/core/time.h"
#include "sim/recorder.h"
#include "sim/version.h"
#include "sim/world_model.h"

namespace uavsim::sim {
namespace {

volatile std::sig_atomic_t g_interrupt = 0;

extern "C" void OnSignal(int) { g_interrupt = 1; }

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

const char* const kModalities[] = {"camera", "lidar", "radar"};

// Per-modality byte counters for the data-rate table (paper Table II).
struct ByteCounters {
  std::map<std::string, std::uint64_t> raw, preprocessed, compressed;
};

// What a node's message carries besides its latent: the pre-processed
// measurement, for the edge's classical filter. The uplink decides its fate
// together with the latent's (same packet).
struct NodeContent {
  std::string node_id;
  std::optional<pipeline::CameraObservation> camera;
  std::optional<pipeline::PointObservation> points;
  std::vector<float> latent;  // the IB-CC mu, when uavloc runs and something was found
  std::size_t sample = 0;     // index in the collected episode, when collecting
};

// The trained model a scenario names, loaded for the run loop. Throws
// core::ConfigError naming the scenario's /pipeline/model when it is missing
// or does not fit the scenario.
std::unique_ptr<pipeline::UavLocModelFiles> LoadModel(const Scenario& s, const std::string& file,
                                                      bool quiet, core::Json& info) {
  namespace fs = std::filesystem;
  const bool is_default = s.pipeline.model == "default";
  const std::string path =
      is_default ? pipeline::DefaultModelPath()
                 : pipeline::ModelManifestPath(
                       (fs::path(s.base_dir) / s.pipeline.model).lexically_normal().string());
  const std::string how =
      "train one with `uavsim train SCENARIO.json --out DIR` and set /pipeline/model to DIR";
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    throw core::ConfigError(file, "/pipeline/model", "no trained model at " + path + ": " + how);
  std::unique_ptr<pipeline::UavLocModelFiles> model;
  try {
    model = pipeline::UavLocModelFiles::Load(path);
  } catch (const core::ConfigError& e) {
    throw core::ConfigError(file, "/pipeline/model", std::string(e.what()) + " (" + how + ")");
  }
  const pipeline::ModelManifest& m = model->manifest();
  if (m.latent_dim != s.pipeline.latent_dim)
    throw core::ConfigError(file, "/pipeline/latent_dim",
                            "the model " + path + " sends latents of " +
                                std::to_string(m.latent_dim) + " values, the scenario asks for " +
                                std::to_string(s.pipeline.latent_dim) + ": " + how);
  if (std::abs(m.window_s - s.pipeline.window_s) > 1e-12)
    throw core::ConfigError(file, "/pipeline/window_s",
                            "the model " + path + " was trained with " +
                                core::FormatNumber(m.window_s) +
                                " s windows, the scenario asks for " +
                                core::FormatNumber(s.pipeline.window_s) + " s: " + how);
  const bool same_layout = m.layout_hash == LayoutHash(s);
  if (!same_layout && !quiet)
    std::cerr << "uavsim: warning: the model " << path << " was trained for scenario \""
              << m.scenario << "\" with another world or node layout; its estimates may be poor ("
              << how << ")\n";
  info = {{"path", path},
          {"trained_for", m.scenario},
          {"same_layout", same_layout},
          {"head", model->edge().anchored() ? "anchored" : "paper"}};
  return model;
}

// Whether a node's pre-processing found anything to send.
bool FoundSomething(const NodeContent& c) {
  return (c.camera && c.camera->detected) || (c.points && c.points->count() > 0);
}

// Bytes a pre-processed observation takes: the two ROI crops at 8 bits plus
// their geometry, or the points as float32.
std::uint64_t PreprocessedBytes(const NodeContent& c) {
  if (!FoundSomething(c)) return 0;  // nothing to send
  if (c.camera)
    return 2ull * pipeline::CameraObservation::kCropPx * pipeline::CameraObservation::kCropPx + 64;
  if (c.points) return 4ull * c.points->values.size();
  return 0;
}

// Root mean square of the Euclidean errors.
struct RmseAccumulator {
  double sum_sq = 0.0;
  std::size_t count = 0;
  void Add(const Eigen::Vector3d& error) { sum_sq += error.squaredNorm(), ++count; }
  double value() const { return count ? std::sqrt(sum_sq / static_cast<double>(count)) : 0.0; }
};

// One sensing node: its sensor model, its noise stream and its frame clock.
struct Node {
  const NodeConfig* config = nullptr;
  std::uint32_t index = 0;
  channel::Modality modality = channel::Modality::kCamera;
  std::unique_ptr<sensors::FisheyeStereo> camera;
  std::unique_ptr<sensors::Lidar> lidar;
  std::unique_ptr<sensors::FmcwRadar> radar;
  std::unique_ptr<sensors::RadarProcessor> radar_processor;
  std::unique_ptr<pipeline::CameraPreprocessor> camera_pre;
  std::unique_ptr<pipeline::LidarPreprocessor> lidar_pre;
  std::unique_ptr<pipeline::RadarPreprocessor> radar_pre;
  core::RngStream noise{0};
  std::uint64_t sequence = 0;
  std::unique_ptr<core::PeriodicProcess> clock;
};

}  // namespace

void InstallInterruptHandlers() {
  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

void ThrowIfInterrupted() {
  if (g_interrupt) throw Interrupted();
}

bool InterruptRequested() { return g_interrupt != 0; }

RunSummary RunScenario(const Scenario& s, const RunOptions& o) {
  const auto wall_start = std::chrono::steady_clock::now();
  const std::string started_utc = UtcNow();
  // Collecting training data writes nothing.
  std::optional<results::RunDirectory> dir;
  std::optional<Recorder> recorder;
  if (!o.collect) {
    dir.emplace(o.out_dir, o.force);
    recorder.emplace(*dir, std::set<std::string>(o.record.begin(), o.record.end()));
  }
  const auto records = [&recorder](const char* m) { return recorder && recorder->Wants(m); };

  WorldModel world(s);
  core::Simulator sim;
  const core::SimTime t_end = core::Seconds(s.duration_s);

  // Ground truth of the target, sampled on its own timer.
  results::CsvTable truth({"t_s", "x_m", "y_m", "z_m", "vx_mps", "vy_mps", "vz_mps"});
  core::PeriodicProcess truth_timer(
      s.outputs.truth_rate_hz, 0.0, [&](std::int64_t, core::SimTime t) {
        if (o.collect) return;
        const auto x = world.target().StateAt(core::ToSeconds(t));
        using results::FormatFixed;
        truth.AddRow({FormatFixed(core::ToSeconds(t), 6), FormatFixed(x.position_m.x(), 6),
                      FormatFixed(x.position_m.y(), 6), FormatFixed(x.position_m.z(), 6),
                      FormatFixed(x.velocity_mps.x(), 6), FormatFixed(x.velocity_mps.y(), 6),
                      FormatFixed(x.velocity_mps.z(), 6)});
      });
  truth_timer.Start(sim, 0, t_end);

  // The edge's localization methods. `ekf` fuses the pre-processed
  // measurements that arrive in time; `uavloc` needs a trained model.
  const auto runs = [&](const char* method) {
    return std::find(s.pipeline.methods.begin(), s.pipeline.methods.end(), method) !=
           s.pipeline.methods.end();
  };
  std::unique_ptr<pipeline::Ekf> ekf;
  if (runs("ekf")) {
    pipeline::EkfConfig config = s.pipeline.ekf;
    config.max_speed_mps = s.uavs.front().trajectory.max_speed_mps;
    config.max_accel_mps2 = s.uavs.front().trajectory.max_accel_mps2;
    config.target_size_m = s.uavs.front().size_m;
    ekf = std::make_unique<pipeline::Ekf>(config);
    for (const NodeConfig& n : s.nodes) {
      switch (n.sensor.type) {
        case sensors::SensorType::kFisheyeStereo:
          ekf->AddCamera(n.id, n.sensor.fisheye);
          break;
        case sensors::SensorType::kLidar:
          ekf->AddLidar(n.id, n.sensor.lidar);
          break;
        case sensors::SensorType::kFmcwRadar:
          ekf->AddRadar(n.id, n.sensor.radar);
          break;
      }
    }
  }

  // The learned pipeline: an IB-CC encoder per modality at the nodes, the
  // edge network at each window deadline on the latents that arrived in time.
  std::unique_ptr<pipeline::UavLocModelFiles> uavloc;
  core::Json model_info;
  // Single-modality ablations: the same network on one modality's latents,
  // each with its own track state.
  std::map<std::string, std::pair<channel::Modality, std::unique_ptr<pipeline::EdgeLocalizer>>>
      ablations;
  const bool any_uavloc =
      runs("uavloc") || runs("uavloc_camera") || runs("uavloc_lidar") || runs("uavloc_radar");
  if (any_uavloc && !o.collect) {
    pipeline::InitTorch(1, s.seed);
    uavloc = LoadModel(s, o.scenario_file, o.quiet, model_info);
    uavloc->edge().WaitForTrack(s.pipeline.uavloc_wait_for_track);
    for (const char* m : kModalities)
      if (const std::string method = std::string("uavloc_") + m; runs(method.c_str()))
        ablations[method] = {*channel::ModalityFromName(m), uavloc->LoadEdge()};
  }
  const core::SimTime window_ns = core::Seconds(s.pipeline.window_s);
  std::map<std::int64_t, pipeline::WindowInputs> pending;  // window k -> latents arrived

  // Uplinks (one per entry of /links, shared by the nodes that name it) and
  // the edge server's reception accounting.
  std::vector<std::string> node_ids;
  for (const NodeConfig& n : s.nodes) node_ids.push_back(n.id);
  channel::EdgeReceiver edge(s.pipeline.window_s, s.pipeline.late_allowance_s);
  std::map<std::string, std::unique_ptr<channel::Uplink>> links;
  for (const auto& [name, config] : s.links) {
    auto link = std::make_unique<channel::Uplink>(
        sim, config, s.weather, core::RngStream(s.seed, "link/" + name), node_ids);
    link->SetArrivalCallback([&](const channel::Message& m, core::SimTime t) {
      if (!edge.OnArrival(m, t) || !m.content) return;  // late: treated as missing
      const auto& content = *static_cast<const NodeContent*>(m.content.get());
      if (o.collect && FoundSomething(content)) o.collect->samples[content.sample].on_time = true;
      if (ekf && content.camera) ekf->Observe(content.node_id, *content.camera);
      if (ekf && content.points) ekf->Observe(content.node_id, *content.points);
      if (uavloc && !content.latent.empty()) {
        const std::int64_t k = m.t_capture_ns / window_ns + 1;
        pipeline::WindowInputs& w = pending[k];
        w.window = k;
        w.frames[static_cast<int>(m.modality)].push_back(
            {core::ToSeconds(m.t_capture_ns), content.latent,
             content.camera ? pipeline::AnchorOf(*content.camera)
                            : pipeline::AnchorOf(*content.points)});
      }
    });
    link->SetLossCallback(
        [&edge](const channel::Message& m, channel::LossCause) { edge.OnLost(m); });
    links.emplace(name, std::move(link));
  }

  // Sensing nodes. Each frame: pose the world at the capture time, capture,
  // record, and send the node's message (its IB latent: latent_dim float32
  // and a header) on its uplink.
  ByteCounters bytes;
  std::map<std::string, std::uint64_t> frames;
  for (const char* m : kModalities)
    frames[m] = 0, bytes.raw[m] = 0, bytes.preprocessed[m] = 0, bytes.compressed[m] = 0;
  // An anchored model's nodes send their geometric anchor too.
  const auto message_bytes = [&](channel::Modality m) {
    return channel::LatentMessageBytes(s.pipeline.latent_dim) +
           (uavloc && uavloc->edge().anchored() ? pipeline::AnchorBytes(m) : 0);
  };
  if (o.collect) {
    o.collect->window_s = s.pipeline.window_s;
    o.collect->samples.clear();
    o.collect->window_truth.clear();
  }
  auto small_objects = [&world](double t_s) {
    std::vector<sensors::BoundingSphere> spheres;
    for (std::size_t i = 0; i < world.uav_count(); ++i)
      spheres.push_back({world.uav(i).StateAt(t_s).position_m, world.uav_radius_m(i)});
    for (std::size_t i = 0; i < world.bird_count(); ++i)
      spheres.push_back({world.bird(i).StateAt(t_s).position_m, world.bird_radius_m(i)});
    return spheres;
  };
  std::vector<std::unique_ptr<Node>> nodes;
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    auto node = std::make_unique<Node>();
    Node& n = *node;
    n.config = &s.nodes[i];
    n.index = static_cast<std::uint32_t>(i);
    n.modality = *channel::ModalityFromName(n.config->sensor.modality());
    n.noise = core::RngStream(s.seed, "node/" + n.config->id + "/noise");
    switch (n.config->sensor.type) {
      case sensors::SensorType::kFisheyeStereo:
        n.camera =
            std::make_unique<sensors::FisheyeStereo>(n.config->sensor.fisheye, world.scene());
        n.camera->set_small_objects(small_objects);
        n.camera_pre = std::make_unique<pipeline::CameraPreprocessor>(n.config->sensor.fisheye,
                                                                      s.pipeline.preprocess);
        break;
      case sensors::SensorType::kLidar:
        n.lidar = std::make_unique<sensors::Lidar>(n.config->sensor.lidar, world.scene());
        n.lidar_pre = std::make_unique<pipeline::LidarPreprocessor>(n.config->sensor.lidar,
                                                                    s.pipeline.preprocess);
        break;
      case sensors::SensorType::kFmcwRadar:
        n.radar = std::make_unique<sensors::FmcwRadar>(n.config->sensor.radar, world.scene());
        n.radar_processor = std::make_unique<sensors::RadarProcessor>(n.config->sensor.radar);
        n.radar_pre = std::make_unique<pipeline::RadarPreprocessor>(n.config->sensor.radar,
                                                                    s.pipeline.preprocess);
        break;
    }
    const auto& timing = n.config->sensor.timing();
    channel::Uplink* link = links.at(n.config->uplink).get();
    n.clock = std::make_unique<core::PeriodicProcess>(
        timing.rate_hz, timing.phase_s, timing.clock_jitter_s,
        core::RngStream(s.seed, "node/" + n.config->id + "/clock"),
        [&, link, node_ptr = &n](std::int64_t, core::SimTime t) {
          Node& nd = *node_ptr;
          const std::string modality = nd.config->sensor.modality();
          const double t_s = core::ToSeconds(t);
          std::uint64_t raw = 0;
          auto content = std::make_shared<NodeContent>();
          content->node_id = nd.config->id;
          if (nd.camera) {
            world.scene().SetTime(t_s);
            const sensors::StereoFrame frame = nd.camera->Capture(t_s, s.weather, nd.noise);
            raw = frame.RawBytes();
            if (records("camera")) recorder->RecordCamera(nd.config->id, frame);
            content->camera = nd.camera_pre->Process(frame);
          } else if (nd.lidar) {
            const sensors::PointCloudFrame frame = nd.lidar->Capture(t_s, s.weather, nd.noise);
            raw = frame.RawBytes();
            if (records("lidar")) recorder->RecordLidar(nd.config->id, frame);
            content->points = nd.lidar_pre->Process(frame);
          } else if (nd.radar) {
            world.scene().SetTime(t_s);
            const sensors::RadarCube cube = nd.radar->Synthesize(
                nd.radar->FindScatterers(t_s, small_objects(t_s)), s.weather, nd.noise);
            const sensors::RadarFrame frame =
                nd.radar_processor->Process(cube, nd.radar->X_WR(), t_s);
            raw = cube.RawBytes();
            if (records("radar")) recorder->RecordRadar(nd.config->id, frame);
            content->points = nd.radar_pre->Process(frame);
          }
          // The node sends its latent when it found something, else a bare
          // header ("nothing seen").
          const bool found = FoundSomething(*content);
          if (found && uavloc) {
            const pipeline::NodeEncoder& enc = uavloc->encoder(nd.modality);
            content->latent =
                content->camera ? enc.Encode(*content->camera) : enc.Encode(*content->points);
          }
          if (found && o.collect) {
            pipeline::Sample sample;
            sample.modality = nd.modality;
            sample.node = nd.index;
            sample.t_s = t_s;
            sample.truth_m = world.target().StateAt(t_s).position_m;
            sample.camera = content->camera;
            sample.points = content->points;
            content->sample = o.collect->samples.size();
            o.collect->samples.push_back(std::move(sample));
          }
          // The latent travels, not the crops: the edge's filter needs the geometry only.
          if (content->camera)
            content->camera->crop_left.clear(), content->camera->crop_right.clear();
          const std::uint32_t bytes_sent =
              found ? message_bytes(nd.modality) : channel::kMessageHeaderBytes;
          ++frames[modality];
          bytes.raw[modality] += raw;
          bytes.preprocessed[modality] += PreprocessedBytes(*content);
          bytes.compressed[modality] += bytes_sent;
          channel::Message m;
          m.node = nd.index;
          m.modality = nd.modality;
          m.sequence = nd.sequence++;
          m.t_capture_ns = t;
          m.payload_bytes = bytes_sent;
          m.content = std::move(content);
          edge.OnSent(m);
          link->Send(std::move(m));
        });
    n.clock->Start(sim, 0, t_end);
    nodes.push_back(std::move(node));
  }

  // At every alignment window's deadline (its end plus the late allowance)
  // the edge estimates the target's position at the window's end from
  // whatever arrived; the base station then steers at each estimate and the
  // downlink is scored. A method scores gain 0 in windows where it has no
  // estimate yet.
  const double rain_db_per_km = channel::RainSpecificAttenuationDbPerKm(
      s.base_station.carrier_ghz, s.weather.rain_mm_h, channel::Polarization::kVertical, 0.0);
  std::vector<std::string> steered;
  if (uavloc && runs("uavloc")) steered.push_back("uavloc");
  if (ekf) steered.push_back("ekf");
  channel::DownlinkScorer downlink(
      s.base_station, rain_db_per_km, steered,
      channel::SnrGridDb(s.outputs.snr_db.from, s.outputs.snr_db.to, s.outputs.snr_db.step),
      core::RngStream(s.seed, "base_station/downlink"));
  results::CsvTable estimates({"t_s", "method", "x_m", "y_m", "z_m"});
  std::map<std::string, RmseAccumulator> rmse, rmse_common;
  const core::SimTime allowance = core::Seconds(s.pipeline.late_allowance_s);
  std::uint64_t windows = 0;  // deadlines the edge estimated at
  core::PeriodicProcess window_timer(
      1.0 / s.pipeline.window_s, s.pipeline.window_s + s.pipeline.late_allowance_s,
      [&](std::int64_t tick, core::SimTime t_deadline) {
        const double t_s = core::ToSeconds(t_deadline - allowance);  // the window's end
        const Eigen::Vector3d truth_m = world.target().StateAt(t_s).position_m;
        if (o.collect) {
          if (t_deadline - allowance <= t_end) o.collect->window_truth.push_back(truth_m);
          return;
        }
        ++windows;
        std::map<std::string, Eigen::Vector3d> estimated;
        if (uavloc) {
          const std::int64_t k = tick + 1;
          pipeline::WindowInputs inputs;
          inputs.window = k;
          if (auto it = pending.find(k); it != pending.end()) inputs = std::move(it->second);
          // Windows up to k are done (an arrival stamped exactly at a passed
          // deadline would otherwise linger).
          pending.erase(pending.begin(), pending.upper_bound(k));
          for (auto& [method, ablation] : ablations) {
            pipeline::WindowInputs one;
            one.window = k;
            const int m = static_cast<int>(ablation.first);
            one.frames[m] = inputs.frames[m];
            if (const auto p = ablation.second->OnWindow(one)) estimated[method] = *p;
          }
          if (runs("uavloc"))
            if (const auto p = uavloc->edge().OnWindow(inputs)) estimated["uavloc"] = *p;
        }
        if (ekf) {
          if (const auto p = ekf->EstimateAt(t_s)) estimated["ekf"] = *p;
        }
        for (const auto& [method, p] : estimated) {
          using results::FormatFixed;
          estimates.AddRow({FormatFixed(t_s, 6), method, FormatFixed(p.x(), 6),
                            FormatFixed(p.y(), 6), FormatFixed(p.z(), 6)});
          rmse[method].Add(p - truth_m);
        }
        if (s.pipeline.methods.size() >= 2 && estimated.size() == s.pipeline.methods.size())
          for (const auto& [method, p] : estimated) rmse_common[method].Add(p - truth_m);
        world.scene().SetTime(t_s);
        std::map<std::string, Eigen::Vector3d> steering;  // the ablations steer no beam
        for (const std::string& beam : steered)
          if (auto it = estimated.find(beam); it != estimated.end()) steering.insert(*it);
        downlink.AddWindow(truth_m, steering, world);
      });
  window_timer.Start(sim, 0, t_end + 1);  // a deadline at exactly t_end still runs

  // Once per simulated second: progress, and a look for termination signals.
  core::Progress progress("run " + s.name, s.duration_s, "sim s", o.quiet);
  bool interrupted = false;
  core::PeriodicProcess housekeeping(1.0, 0.0, [&](std::int64_t, core::SimTime t) {
    progress.Update(core::ToSeconds(t));
    if (g_interrupt) interrupted = true, sim.Stop();
  });
  housekeeping.Start(sim, 0, t_end);

  sim.RunUntil(t_end);
  if (interrupted || g_interrupt) throw Interrupted();
  progress.Finish();

  RunSummary summary;
  summary.sim_s = s.duration_s;
  summary.truth_rows = truth.rows();
  summary.frames = frames;
  summary.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  for (const std::string& method : s.pipeline.methods) rmse[method];
  for (const auto& [method, acc] : rmse)
    summary.rmse_m[method] = acc.count ? std::optional<double>(acc.value()) : std::nullopt;
  for (const auto& [method, acc] : rmse_common) {
    summary.rmse_common_m[method] = acc.value();
    summary.common_windows = acc.count;
  }
  if (o.collect) return summary;

  dir->WriteText("truth.csv", truth.str());
  dir->WriteText("estimates.csv", estimates.str());
  dir->WriteText("rate_snr.csv", downlink.rates().Csv());
  results::PlotSpec plot;
  plot.title = "Achievable rate vs SNR (" + s.name + ")";
  plot.x_label = "SNR (dB)";
  plot.y_label = "Rate (bit/s/Hz)";
  plot.x_column = "snr_db";
  plot.y_column = "rate_bps_hz";
  plot.group_column = "beam";
  plot.png_path = dir->StagingPath("rate_snr.png");
  if (const std::string err = results::PlotCsv(dir->StagingPath("rate_snr.csv"), plot);
      !err.empty() && !o.quiet)
    std::cerr << "uavsim: warning: rate_snr.png not drawn: " << err << "\n";
  recorder->Finish();

  core::Json metrics = core::Json::object();
  // Every method that ran has an entry; null when it never produced an
  // estimate (e.g. a run shorter than the filter's warm-up).
  core::Json rmse_json = core::Json::object();
  core::Json windows_json = core::Json::object();
  for (const auto& [method, acc] : rmse) {
    rmse_json[method] = acc.count ? core::Json(acc.value()) : core::Json(nullptr);
    windows_json[method] = acc.count;
  }
  metrics["rmse_m"] = rmse_json;
  metrics["windows"] = windows;
  metrics["estimated_windows"] = windows_json;
  // Methods compared on the same windows: those every method estimated.
  metrics["common_windows"] = summary.common_windows;
  core::Json common_json = core::Json::object();
  for (const auto& [method, value] : summary.rmse_common_m) common_json[method] = value;
  metrics["rmse_common_m"] = common_json;
  if (uavloc) metrics["uavloc_model"] = model_info;
  core::Json modalities = core::Json::object();
  for (const auto& [m, n] : frames) modalities[m] = {{"frames", n}};
  edge.WriteMetrics(modalities);
  metrics["modalities"] = modalities;
  core::Json rates = core::Json::object();
  for (const char* m : kModalities)
    rates[m] = {{"raw", bytes.raw[m] / 1000.0 / s.duration_s},
                {"preprocessed", bytes.preprocessed[m] / 1000.0 / s.duration_s},
                {"compressed", bytes.compressed[m] / 1000.0 / s.duration_s}};
  metrics["data_rate_kBps"] = rates;
  metrics["sim_s"] = summary.sim_s;
  metrics["wall_s"] = summary.wall_s;
  metrics["realtime_factor"] = summary.wall_s > 0 ? summary.sim_s / summary.wall_s : 0.0;
  dir->WriteJson("metrics.json", metrics);

  core::Json manifest = core::Json::object();
  manifest["uavsim_version"] = Version();
  manifest["git_hash"] = GitHash();
  manifest["scenario_file"] = o.scenario_file;
  manifest["seed"] = s.seed;
  manifest["started_utc"] = started_utc;
  manifest["wall_s"] = summary.wall_s;
  manifest["scenario"] = ResolvedJson(s);
  dir->WriteJson("manifest.json", manifest);

  dir->Commit();
  return summary;
}

}  // namespace uavsim::sim
