// A sensing node as the run wires it (DESIGN.md: sensors -> pipeline/node ->
// channel/uplink): at each tick of its own frame clock the node's sensor
// captures the world, the node pre-processes the frame (pipeline/node/),
// encodes what it found with its modality's IB-CC encoder when a model runs,
// and sends one message on its uplink.
//
// Determinism: a node draws sensor noise from its own stream
// "node/<id>/noise" and clock jitter from "node/<id>/clock"; its frames are
// numbered 0, 1, 2, ... in capture order.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "channel/edge_receiver.h"
#include "channel/packet.h"
#include "channel/uplink.h"
#include "core/periodic_process.h"
#include "core/rng.h"
#include "core/simulator.h"
#include "core/wall_profile.h"
#include "pipeline/node/node_encoder.h"
#include "pipeline/node/observations.h"
#include "sim/node_content.h"
#include "sim/scenario.h"

namespace uavsim::sim {

class Recorder;
class WorldModel;
class SensingTraceReader;
class SensingTraceWriter;
struct TracedFrame;

// A sensor behind one interface, in two stages: Acquire poses its view of
// the world at t_s and captures (drawing from `noise`); the function it
// returns pre-processes that capture and says how to record the raw frame
// when the run records this modality. Acquire touches only the sensor's own
// state and the noise stream it is given, the pre-processing only the
// node's pre-processor: nodes may capture on threads of their own, and a
// node may capture frame k + 1 while frame k is pre-processed (captures in
// frame order, one at a time; pre-processings likewise). The public methods
// keep the checks; each sensor's work is its private DoAcquire (ns-3's
// CalcRxPower / DoCalcRxPower).
struct NodeFrame {
  std::uint64_t raw_bytes = 0;       // the raw frame (or radar cube) as the sensor produced it
  NodeContent content;               // its pre-processed content
  std::optional<TargetSight> sight;  // point modalities only
  // Writes the raw frame to the run's recorder (empty: not recorded). The
  // node calls it on the event loop's thread, in capture order, so frames
  // are numbered as without threads.
  std::function<void()> record;
};

class NodeSensor {
 public:
  // Pre-processes one capture; throws std::logic_error if the
  // pre-processing gave neither or both observation kinds. A frame may
  // hold no raw data (a LiDAR whose beams hit nothing): raw_bytes 0.
  using Preprocess = std::function<NodeFrame()>;
  virtual ~NodeSensor() = default;
  Preprocess Acquire(double t_s, core::RngStream& noise);
  // Both stages at once.
  NodeFrame Capture(double t_s, core::RngStream& noise);

 private:
  virtual Preprocess DoAcquire(double t_s, core::RngStream& noise) = 0;
};

// The node's sensor for its configuration: the stereo fisheye camera, the
// LiDAR or the FMCW radar with the node's pre-processing. `recorder` may be
// null (nothing recorded); `world` outlives the sensor. With a `profile`
// the sensor times its capture ("node/<id>/capture") and pre-processing
// ("node/<id>/preprocess") into it (parts made here, so that a capture on
// another thread only adds to its own).
std::unique_ptr<NodeSensor> MakeNodeSensor(const NodeConfig& node, const Scenario& scenario,
                                           WorldModel& world, Recorder* recorder,
                                           core::WallProfile* profile = nullptr);

// Bytes per modality over a run: the data-rate table (paper Table II).
struct NodeTraffic {
  std::uint64_t frames = 0;
  std::uint64_t raw_bytes = 0;
  std::uint64_t preprocessed_bytes = 0;
  std::uint64_t compressed_bytes = 0;  // what the uplink carried (headers included)
  // Point modalities (TargetSight): frames whose raw data saw the target,
  // frames that sent something, of those the ones holding the target, and
  // frames that saw the target and sent it.
  std::uint64_t target_frames = 0, sent_frames = 0, sent_on_target = 0, target_frames_sent = 0;
};

class SensingNode {
 public:
  // Called with each frame's content after encoding, before it is sent (a
  // training collector tags it); may be empty.
  using FrameObserver = std::function<void(const SensingNode&, double t_s, NodeContent&)>;
  struct Wiring {
    channel::Uplink* link = nullptr;                 // where the messages go
    channel::EdgeReceiver* receiver = nullptr;       // the edge's accounting of what was sent
    const pipeline::NodeEncoder* encoder = nullptr;  // null: no latent (no model runs)
    std::uint32_t message_bytes = 0;  // a message that carries something (header included)
    FrameObserver observer;
    core::WallProfile* profile = nullptr;  // times recording and encoding ("node/<id>/...")
    // Sensing traces (sim/sensing_trace.h): each frame as sent is added to
    // `trace`; with `replay` the node takes its frames from there instead of
    // sensing (it then needs no sensor, and nothing is recorded or observed).
    SensingTraceWriter* trace = nullptr;
    SensingTraceReader* replay = nullptr;
  };

  // `index`: the node's position in the scenario's node list; `sensor` may
  // be null when the wiring replays a trace. With the
  // scenario's execution.parallel_nodes, the node makes its next two frames
  // on threads of their own ahead of their time, while the event loop runs
  // (the same frames, byte for byte).
  SensingNode(const NodeConfig& config, std::uint32_t index, std::unique_ptr<NodeSensor> sensor,
              const Scenario& scenario, Wiring wiring);
  ~SensingNode();
  SensingNode(const SensingNode&) = delete;
  SensingNode& operator=(const SensingNode&) = delete;

  // Starts the frame clock: frames at the sensor's rate, phase and clock
  // jitter over [0, t_end].
  void Start(core::Simulator& sim, core::SimTime t_end);

  const NodeConfig& config() const { return config_; }
  std::uint32_t index() const { return index_; }
  core::Modality modality() const { return modality_; }
  const NodeTraffic& traffic() const { return traffic_; }

 private:
  // A frame in the making (execution.parallel_nodes): its time, the ends
  // of its two stages (the next frame's stages wait for them) and the
  // frame.
  struct Ahead {
    core::SimTime t = 0;
    std::shared_future<void> acquired, preprocessed;
    std::future<NodeFrame> frame;
  };
  void OnFrame(core::SimTime t);
  // A frame sensed, recorded, encoded and observed, as it is sent.
  TracedFrame SenseFrame(core::SimTime t);
  // Accounts a frame and sends its message.
  void Send(core::SimTime t, TracedFrame frame);
  NodeFrame TakeFrame(core::SimTime t);
  NodeFrame TakeFrameNamed(core::SimTime t);
  void MakeAhead(core::SimTime t);

  const NodeConfig& config_;
  std::uint32_t index_;
  core::Modality modality_;
  std::unique_ptr<NodeSensor> sensor_;
  Wiring wiring_;
  core::RngStream noise_;
  std::uint64_t sequence_ = 0;
  NodeTraffic traffic_;
  core::PeriodicProcess clock_;
  bool ahead_of_time_;
  std::deque<Ahead> ahead_;  // the next two frames, oldest first
};

}  // namespace uavsim::sim
