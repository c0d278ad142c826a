#include "sim/sensing_node.h"

#include <new>
#include <optional>
#include <stdexcept>
#include <utility>

#include "core/error.h"
#include "core/interrupt.h"
#include "core/json_io.h"
#include "pipeline/node/camera_preprocessor.h"
#include "pipeline/node/lidar_preprocessor.h"
#include "pipeline/node/radar_preprocessor.h"
#include "sensors/fisheye_stereo.h"
#include "sensors/fmcw_radar.h"
#include "sensors/lidar.h"
#include "sensors/radar_processor.h"
#include "sim/lidar_survey.h"
#include "sim/recorder.h"
#include "sim/sensing_trace.h"
#include "sim/world_model.h"

namespace uavsim::sim {
namespace {

// What every node sensor needs besides its model: its node's id, the
// weather, the world, its own view of the world's scene (so that nodes may
// capture on threads of their own), where it records (null: nowhere) and
// where it times its work (null: nowhere).
constexpr double kLidarTargetRadiusM = 1.0;
constexpr double kRadarTargetRadiusM = 3.0;

bool Near(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double radius_m) {
  return (p - q).squaredNorm() <= radius_m * radius_m;
}

// Whether an observation's points (x, y, z first) hold one within the
// radius of where the target was at `time_of(i)`.
template <class TimeOf>
bool HoldsTarget(const pipeline::PointObservation& obs, const core::Trajectory& target,
                 double radius_m, TimeOf time_of) {
  for (std::size_t i = 0; i < obs.count(); ++i) {
    const float* v = &obs.values[i * static_cast<std::size_t>(obs.channels)];
    if (Near({v[0], v[1], v[2]}, target.StateAt(time_of(i)).position_m, radius_m)) return true;
  }
  return false;
}

// The further point observations into the content (the found ones).
void AddFurther(NodeContent& content, std::vector<pipeline::PointObservation>& further) {
  for (auto& o : further)
    if (o.count() > 0) content.further.push_back({{}, std::move(o), {}});
}

TargetSight LidarSight(const WorldModel& world, const sensors::PointCloudFrame& frame,
                       const pipeline::PointObservation& sent) {
  TargetSight s;
  const core::Trajectory& target = world.target();
  for (const sensors::LidarPoint& p : frame.points)
    if (Near({p.x_m, p.y_m, p.z_m}, target.StateAt(frame.t_start_s + p.t_offset_s).position_m,
             kLidarTargetRadiusM)) {
      s.frame_saw = true;
      break;
    }
  // The observation keeps no per-point times; its t_s is their mean.
  s.sent_holds =
      HoldsTarget(sent, target, kLidarTargetRadiusM, [&](std::size_t) { return sent.t_s; });
  return s;
}

TargetSight RadarSight(const WorldModel& world, const sensors::RadarFrame& frame,
                       const pipeline::PointObservation& sent) {
  TargetSight s;
  const Eigen::Vector3d truth = world.target().StateAt(frame.t_capture_s).position_m;
  for (const sensors::RadarPoint& p : frame.points)
    if (Near({p.x_m, p.y_m, p.z_m}, truth, kRadarTargetRadiusM)) {
      s.frame_saw = true;
      break;
    }
  s.sent_holds = HoldsTarget(sent, world.target(), kRadarTargetRadiusM,
                             [&](std::size_t) { return frame.t_capture_s; });
  return s;
}

struct SensorContext {
  SensorContext(const std::string& id, const core::WeatherConfig& weather, WorldModel& world,
                Recorder* recorder, core::WallProfile* profile)
      : id(id),
        weather(weather),
        world(world),
        scene(world.scene().NewView()),
        recorder(recorder),
        capture(profile ? &profile->part("node/" + id + "/capture") : nullptr),
        preprocess(profile ? &profile->part("node/" + id + "/preprocess") : nullptr) {}

  const std::string& id;
  const core::WeatherConfig& weather;
  WorldModel& world;
  std::unique_ptr<sensors::RaycastScene> scene;
  Recorder* recorder;
  // Made here, on the event loop's thread: a capture ahead of time only adds
  // to its own parts.
  core::WallProfile::Part* capture;
  core::WallProfile::Part* preprocess;
};

class CameraNodeSensor final : public NodeSensor {
 public:
  CameraNodeSensor(const NodeConfig& node, const Scenario& s, SensorContext c)
      : c_(std::move(c)),
        camera_(node.sensor.fisheye, *c_.scene),
        preprocess_(node.sensor.fisheye, s.pipeline.preprocess) {
    WorldModel& world = c_.world;
    camera_.set_small_objects([&world](double t_s) { return world.SmallObjects(t_s); });
    camera_.set_static_cache(s.execution.static_cache);
  }

 private:
  Preprocess DoAcquire(double t_s, core::RngStream& noise) override {
    auto frame = std::make_shared<sensors::StereoFrame>();
    {
      const core::WallProfile::Scope timing(c_.capture);
      c_.scene->SetTime(t_s);
      *frame = camera_.Capture(t_s, c_.weather, noise);
    }
    return [this, frame] {
      const core::WallProfile::Scope timing(c_.preprocess);
      NodeFrame out{frame->RawBytes(), {}, {}, {}};
      std::vector<pipeline::CameraObservation> further;
      out.content.camera = preprocess_.Process(*frame, &further);
      for (auto& o : further) out.content.further.push_back({std::move(o), {}, {}});
      if (c_.recorder)
        out.record = [recorder = c_.recorder, &id = c_.id, frame] {
          recorder->RecordCamera(id, *frame);
        };
      return out;
    };
  }

  SensorContext c_;
  sensors::FisheyeStereo camera_;
  pipeline::CameraPreprocessor preprocess_;
};

class LidarNodeSensor final : public NodeSensor {
 public:
  LidarNodeSensor(const NodeConfig& node, const Scenario& s, SensorContext c)
      : c_(std::move(c)),
        lidar_(node.sensor.lidar, *c_.scene),
        preprocess_(node.sensor.lidar, s.pipeline.preprocess,
                    s.pipeline.preprocess.weather.Known(c_.weather)) {
    if (s.pipeline.preprocess.lidar.background == pipeline::LidarBackground::kSurvey &&
        !s.pipeline.preprocess.LidarRaw())
      preprocess_.SetStaticMap(
          SurveyStaticScene(node, s, c_.world.geometry(), lidar_, preprocess_).map);
  }

 private:
  // The LiDAR poses the scene at each point's own time.
  Preprocess DoAcquire(double t_s, core::RngStream& noise) override {
    auto frame = std::make_shared<sensors::PointCloudFrame>();
    {
      const core::WallProfile::Scope timing(c_.capture);
      *frame = lidar_.Capture(t_s, c_.weather, noise);
    }
    return [this, frame] {
      const core::WallProfile::Scope timing(c_.preprocess);
      NodeFrame out{frame->RawBytes(), {}, {}, {}};
      std::vector<pipeline::PointObservation> further;
      out.content.points = preprocess_.Process(*frame, &further);
      AddFurther(out.content, further);
      out.sight = LidarSight(c_.world, *frame, *out.content.points);
      if (c_.recorder)
        out.record = [recorder = c_.recorder, &id = c_.id, frame] {
          recorder->RecordLidar(id, *frame);
        };
      return out;
    };
  }

  SensorContext c_;
  sensors::Lidar lidar_;
  pipeline::LidarPreprocessor preprocess_;
};

// The node's radar front end: IF cube, range-Doppler, CFAR, angles
// (sensors/radar_processor.h), then the node's clustering.
class RadarNodeSensor final : public NodeSensor {
 public:
  RadarNodeSensor(const NodeConfig& node, const Scenario& s, SensorContext c)
      : c_(std::move(c)),
        radar_(node.sensor.radar, *c_.scene),
        processor_(node.sensor.radar),
        preprocess_(node.sensor.radar, s.pipeline.preprocess,
                    s.pipeline.preprocess.weather.Known(c_.weather)) {
    radar_.set_static_cache(s.execution.static_cache);
  }

 private:
  Preprocess DoAcquire(double t_s, core::RngStream& noise) override {
    std::uint64_t raw_bytes = 0;
    auto frame = std::make_shared<sensors::RadarFrame>();
    {
      // The radar's capture is the IF cube and its signal processing (the
      // radar's own DSP); the node's pre-processing is the clustering.
      const core::WallProfile::Scope timing(c_.capture);
      c_.scene->SetTime(t_s);
      const sensors::RadarCube cube = radar_.Synthesize(
          radar_.FindScatterers(t_s, c_.world.SmallObjects(t_s)), c_.weather, noise);
      raw_bytes = cube.RawBytes();
      *frame = processor_.Process(cube, radar_.X_WR(), t_s);
    }
    return [this, frame, raw_bytes] {
      const core::WallProfile::Scope timing(c_.preprocess);
      NodeFrame out{raw_bytes, {}, {}, {}};
      std::vector<pipeline::PointObservation> further;
      out.content.points = preprocess_.Process(*frame, &further);
      AddFurther(out.content, further);
      out.sight = RadarSight(c_.world, *frame, *out.content.points);
      if (c_.recorder)
        out.record = [recorder = c_.recorder, &id = c_.id, frame] {
          recorder->RecordRadar(id, *frame);
        };
      return out;
    };
  }

  SensorContext c_;
  sensors::FmcwRadar radar_;
  sensors::RadarProcessor processor_;
  pipeline::RadarPreprocessor preprocess_;
};

}  // namespace

NodeSensor::Preprocess NodeSensor::Acquire(double t_s, core::RngStream& noise) {
  Preprocess preprocess = DoAcquire(t_s, noise);
  if (!preprocess) throw std::logic_error("a sensor's capture gave nothing to pre-process");
  return [preprocess = std::move(preprocess)] {
    // A frame may hold no raw data (a LiDAR that sees nothing: pointed at
    // the sky, too far away, too fast to complete its pattern): the node
    // sends "nothing seen" and the run goes on.
    NodeFrame frame = preprocess();
    if (frame.content.camera.has_value() == frame.content.points.has_value())
      throw std::logic_error("a node's pre-processing gave neither or both observation kinds");
    return frame;
  };
}

NodeFrame NodeSensor::Capture(double t_s, core::RngStream& noise) { return Acquire(t_s, noise)(); }

std::unique_ptr<NodeSensor> MakeNodeSensor(const NodeConfig& node, const Scenario& scenario,
                                           WorldModel& world, Recorder* recorder,
                                           core::WallProfile* profile) {
  const bool records = recorder && recorder->Wants(node.sensor.modality());
  SensorContext c(node.id, scenario.weather, world, records ? recorder : nullptr, profile);
  switch (node.sensor.type) {
    case sensors::SensorType::kFisheyeStereo:
      return std::make_unique<CameraNodeSensor>(node, scenario, std::move(c));
    case sensors::SensorType::kLidar:
      return std::make_unique<LidarNodeSensor>(node, scenario, std::move(c));
    case sensors::SensorType::kFmcwRadar:
      return std::make_unique<RadarNodeSensor>(node, scenario, std::move(c));
  }
  throw std::logic_error("unknown sensor type");
}

SensingNode::SensingNode(const NodeConfig& config, std::uint32_t index,
                         std::unique_ptr<NodeSensor> sensor, const Scenario& scenario,
                         Wiring wiring)
    : config_(config),
      index_(index),
      modality_(*core::ModalityFromName(config.sensor.modality())),
      sensor_(std::move(sensor)),
      wiring_(std::move(wiring)),
      noise_(scenario.seed, "node/" + config.id + "/noise"),
      clock_(config.sensor.timing().rate_hz, config.sensor.timing().phase_s,
             config.sensor.timing().clock_jitter_s,
             core::RngStream(scenario.seed, "node/" + config.id + "/clock"),
             [this](std::int64_t, core::SimTime t) { OnFrame(t); }),
      ahead_of_time_(scenario.execution.parallel_nodes && !wiring_.replay) {
  if (!sensor_ && !wiring_.replay) throw std::logic_error("a sensing node without a sensor");
}

SensingNode::~SensingNode() {
  // Frames in the making use the sensor and the noise stream: wait for them.
  for (Ahead& a : ahead_)
    if (a.frame.valid()) a.frame.wait();
}

void SensingNode::Start(core::Simulator& sim, core::SimTime t_end) {
  clock_.Start(sim, 0, t_end);
  if (!ahead_of_time_) return;
  if (const std::optional<core::SimTime> t = clock_.next_delivery()) MakeAhead(*t);
  if (const std::optional<core::SimTime> t = clock_.delivery_after_next()) MakeAhead(*t);
}

// The node's frames depend on nothing the event loop does (the world is a
// function of time; the sensor, its pre-processing and the noise stream are
// the node's own), so they may be made on threads of their own while the
// loop runs: the frames, and so the run, are the same either way. Two frames
// are in the making at once, a pipeline of two stages: frame k + 1's sensor
// capture runs while frame k is pre-processed. Captures follow one another
// in frame order (the noise stream's draws keep their order), and so do the
// pre-processings (the pre-processor's state, e.g. MOG2's background).
void SensingNode::MakeAhead(core::SimTime t) {
  auto acquired = std::make_shared<std::promise<void>>();
  auto preprocessed = std::make_shared<std::promise<void>>();
  Ahead a;
  a.t = t;
  a.acquired = acquired->get_future().share();
  a.preprocessed = preprocessed->get_future().share();
  std::shared_future<void> previous_acquired, previous_preprocessed;
  if (!ahead_.empty()) {
    previous_acquired = ahead_.back().acquired;
    previous_preprocessed = ahead_.back().preprocessed;
  }
  a.frame = std::async(std::launch::async, [this, t_s = core::ToSeconds(t), previous_acquired,
                                            previous_preprocessed, acquired, preprocessed] {
    // Each stage signals its end whatever happens, so that the next frame's
    // stage never waits forever; an exception reaches TakeFrame.
    NodeSensor::Preprocess preprocess;
    try {
      if (previous_acquired.valid()) previous_acquired.wait();
      preprocess = sensor_->Acquire(t_s, noise_);
    } catch (...) {
      acquired->set_value();
      if (previous_preprocessed.valid()) previous_preprocessed.wait();
      preprocessed->set_value();
      throw;
    }
    acquired->set_value();
    try {
      if (previous_preprocessed.valid()) previous_preprocessed.wait();
      NodeFrame frame = preprocess();
      preprocessed->set_value();
      return frame;
    } catch (...) {
      preprocessed->set_value();
      throw;
    }
  });
  ahead_.push_back(std::move(a));
}

NodeFrame SensingNode::TakeFrame(core::SimTime t) {
  if (ahead_.empty()) return sensor_->Capture(core::ToSeconds(t), noise_);
  Ahead a = std::move(ahead_.front());
  ahead_.pop_front();
  if (a.t != t) throw std::logic_error("a node's frame made ahead is for another time");
  NodeFrame frame = a.frame.get();
  // Inside this tick's callback the clock already foretells the tick after
  // the next one: keep two frames in the making.
  if (const std::optional<core::SimTime> after = clock_.delivery_after_next()) MakeAhead(*after);
  return frame;
}

// A failure inside a frame names the node and the frame's time; a
// termination request, a bad input and an exhausted memory pass unchanged.
NodeFrame SensingNode::TakeFrameNamed(core::SimTime t) {
  try {
    return TakeFrame(t);
  } catch (const core::Interrupted&) {
    throw;
  } catch (const core::ConfigError&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    throw std::runtime_error("node " + config_.id + ", frame at t = " +
                             core::FormatNumber(core::ToSeconds(t)) + " s: " + e.what());
  }
}

void SensingNode::OnFrame(core::SimTime t) {
  TracedFrame frame = wiring_.replay ? wiring_.replay->Take(index_, t) : SenseFrame(t);
  if (wiring_.trace) wiring_.trace->Add(index_, frame);
  Send(t, std::move(frame));
}

TracedFrame SensingNode::SenseFrame(core::SimTime t) {
  const double t_s = core::ToSeconds(t);
  NodeFrame frame = TakeFrameNamed(t);
  if (frame.record) {
    const auto timing =
        core::WallProfile::Measure(wiring_.profile, "node/" + config_.id + "/record");
    frame.record();  // in capture order, on the event loop's thread
  }
  TracedFrame out{t, frame.raw_bytes, frame.sight, std::move(frame.content)};
  NodeContent& content = out.content;
  content.node_id = config_.id;
  // The node sends a latent per observation it found, else a bare header
  // ("nothing seen").
  const bool found = content.Found();
  if (wiring_.encoder && content.FoundSomething()) {
    const auto timing =
        core::WallProfile::Measure(wiring_.profile, "node/" + config_.id + "/encode");
    const auto encode = [&](NodeObservation& o) {
      o.latent = o.camera ? wiring_.encoder->Encode(*o.camera) : wiring_.encoder->Encode(*o.points);
    };
    if (found) encode(content);
    for (NodeObservation& o : content.further) encode(o);
  }
  if (found && wiring_.observer) wiring_.observer(*this, t_s, content);
  // The latents travel, not the crops: the edge's filters need the geometry only.
  const auto clear_crops = [](NodeObservation& o) {
    if (o.camera) o.camera->crop_left.clear(), o.camera->crop_right.clear();
  };
  clear_crops(content);
  for (NodeObservation& o : content.further) clear_crops(o);
  return out;
}

void SensingNode::Send(core::SimTime t, TracedFrame frame) {
  auto content = std::make_shared<NodeContent>(std::move(frame.content));
  content->node_id = config_.id;
  const bool found = content->Found();
  // The header, and per observation its latent (and anchor).
  const std::uint32_t bytes_sent =
      channel::kMessageHeaderBytes + static_cast<std::uint32_t>(content->ObservationCount()) *
                                         (wiring_.message_bytes - channel::kMessageHeaderBytes);
  ++traffic_.frames;
  traffic_.raw_bytes += frame.raw_bytes;
  if (frame.sight) {
    traffic_.target_frames += frame.sight->frame_saw;
    traffic_.sent_frames += found;
    traffic_.sent_on_target += found && frame.sight->sent_holds;
    traffic_.target_frames_sent += frame.sight->frame_saw && found && frame.sight->sent_holds;
  }
  traffic_.preprocessed_bytes += content->PreprocessedBytes();
  traffic_.compressed_bytes += bytes_sent;
  channel::Message m;
  m.node = index_;
  m.modality = modality_;
  m.sequence = sequence_++;
  m.t_capture_ns = t;
  m.payload_bytes = bytes_sent;
  m.content = std::move(content);
  wiring_.receiver->OnSent(m);
  wiring_.link->Send(std::move(m));
}

}  // namespace uavsim::sim
