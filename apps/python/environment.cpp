// uavsim.BeamEnv's engine: a run on a thread of its own that stops at every
// alignment window once it is scored (RunOptions::on_window) and waits
// there for the agent's beam. One step is one window:
//   observation  what reached the edge in the window (each message's node,
//                modality, capture time, latent and detection, the node's
//                geometric anchor), each method's estimate
//   action       a direction from the base station's array (world ENU, any
//                length), or None: the beam of the method `steer_by`
//   reward       log2(1 + SNR gamma) at `snr_db`, gamma the beam's gain on
//                the window's channel (channel/beamformer.h): the per-window
//                term whose mean over the run rate_snr.csv gives
//   info         the truth, the window, every steering method's rate
// The run writes its directory as `uavsim run` does when it ends; closing
// the environment early leaves nothing (the run is interrupted).
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <condition_variable>
#include <mutex>
#include <thread>

#include "apps/python/bindings.h"
#include "channel/beamformer.h"
#include "core/interrupt.h"
#include "sim/edge_server.h"
#include "sim/run.h"
#include "sim/window_scorer.h"

namespace uavsim::python {
namespace {

py::array_t<double> Vec(const Eigen::Vector3d& v) {
  py::array_t<double> a(3);
  for (int i = 0; i < 3; ++i) a.mutable_at(i) = v[i];
  return a;
}

// The gain of the beam steered from the array along `direction` (world ENU)
// on the window's channel.
double GainTowards(const sim::WindowScorer& scorer, const Eigen::Vector3d& direction) {
  const channel::DownlinkScorer& d = scorer.downlink();
  const Eigen::Vector3d& bs = d.channel().config().position_m;
  Eigen::VectorXcd f;
  channel::SteeredBeamInto(d.channel().upa(), bs, bs + 100.0 * direction.normalized(), &f);
  return channel::BeamGain(d.last_channel().h, f);
}

class Stepper {
 public:
  Stepper(ScenarioSource source, std::string out_dir, double snr_db, std::string steer_by,
          bool quiet, py::dict methods)
      : source_(std::move(source)),
        out_dir_(std::move(out_dir)),
        snr_db_(snr_db),
        steer_by_(std::move(steer_by)),
        quiet_(quiet),
        methods_(std::move(methods)),
        hosted_(HostedFrom(methods_)) {}
  ~Stepper() { Stop(); }

  py::object Reset() {
    Stop();
    state_ = State::kRunning;
    finished_ = false;
    error_ = nullptr;
    worker_ = std::thread([this] { Work(); });
    return Await();
  }

  // Scores `action` on the paused window, lets the run go on to the next one.
  py::tuple Step(const py::object& action) {
    if (state_ != State::kPaused) throw py::value_error("step() before reset() or after the end");
    const double gain = ActionGain(action);
    const double reward = channel::RateBpsHz(snr_db_, gain);
    {
      const std::lock_guard<std::mutex> lock(mu_);
      state_ = State::kRunning;
    }
    cv_.notify_all();
    py::object obs = Await();
    const bool terminated = finished_;
    return py::make_tuple(obs, reward, terminated, last_info_);
  }

  void Stop() {
    if (!worker_.joinable()) return;
    {
      const std::lock_guard<std::mutex> lock(mu_);
      if (!finished_) state_ = State::kAbort;
    }
    cv_.notify_all();
    py::gil_scoped_release release;
    worker_.join();
  }

  py::dict info() const { return last_info_; }

 private:
  enum class State { kRunning, kPaused, kAbort };

  void Work() {
    sim::RunOptions o;
    o.out_dir = out_dir_;
    o.force = true;
    o.quiet = quiet_;
    o.report = false;
    o.hosted = &hosted_;
    o.on_window = [this](const sim::WindowView& v) { Pause(v); };
    try {
      const sim::Scenario s = LoadSource(source_);
      o.scenario_file = source_.file();
      sim::CheckTrainedModel(s, source_.file(), quiet_, &hosted_);
      sim::RunScenario(s, o);
    } catch (...) {
      error_ = std::current_exception();
    }
    const std::lock_guard<std::mutex> lock(mu_);
    finished_ = true;
    cv_.notify_all();
  }

  // On the run's thread: publish the window, wait for the agent.
  void Pause(const sim::WindowView& v) {
    std::unique_lock<std::mutex> lock(mu_);
    if (state_ == State::kAbort) throw core::Interrupted();
    view_ = &v;
    state_ = State::kPaused;
    cv_.notify_all();
    cv_.wait(lock, [this] { return state_ != State::kPaused; });
    view_ = nullptr;
    if (state_ == State::kAbort) throw core::Interrupted();
  }

  // Waits (GIL released, Ctrl-C honoured) for the next window or the end.
  py::object Await();
  py::dict Observation(const sim::WindowView& v) const;
  py::dict Info(const sim::WindowView& v) const;
  double ActionGain(const py::object& action) const;

  ScenarioSource source_;
  std::string out_dir_;
  double snr_db_;
  std::string steer_by_;
  bool quiet_;
  py::dict methods_;
  sim::HostedMethods hosted_;
  std::thread worker_;
  std::mutex mu_;
  std::condition_variable cv_;
  State state_ = State::kRunning;
  bool finished_ = false;
  std::exception_ptr error_;
  const sim::WindowView* view_ = nullptr;
  py::object last_obs_ = py::none();
  py::dict last_info_;
};

py::object Stepper::Await() {
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    std::unique_lock<std::mutex> lock(mu_);
    while (!cv_.wait_for(lock, std::chrono::milliseconds(50),
                         [this] { return finished_ || state_ == State::kPaused; })) {
      lock.unlock();
      {
        py::gil_scoped_acquire gil;
        interrupted = PyErr_CheckSignals() != 0;
      }
      lock.lock();
      if (interrupted) break;
    }
  }
  if (interrupted) {
    py::error_already_set signal;  // KeyboardInterrupt, fetched before Stop
    Stop();
    throw signal;
  }
  if (finished_) {
    worker_.join();
    if (error_) std::rethrow_exception(error_);
    return last_obs_;
  }
  last_obs_ = Observation(*view_);
  last_info_ = Info(*view_);
  return last_obs_;
}

py::dict Stepper::Observation(const sim::WindowView& v) const {
  const auto& arrivals = v.edge->last_arrivals();
  const auto n = static_cast<py::ssize_t>(arrivals.size());
  py::ssize_t z = 0;
  for (const auto& a : arrivals)
    z = std::max<py::ssize_t>(z, static_cast<py::ssize_t>(a.latent.size()));
  py::list node;
  py::array_t<int> modality(n), kind(n);
  py::array_t<double> t_capture(n), origin({n, py::ssize_t{3}}), direction({n, py::ssize_t{3}});
  py::array_t<float> latent({n, z});
  for (py::ssize_t i = 0; i < n; ++i) {
    const auto& a = arrivals[static_cast<std::size_t>(i)];
    node.append(a.node_id);
    modality.mutable_at(i) = static_cast<int>(a.modality);
    kind.mutable_at(i) = static_cast<int>(a.anchor.kind);
    t_capture.mutable_at(i) = a.t_capture_s;
    for (int c = 0; c < 3; ++c) {
      origin.mutable_at(i, c) = a.anchor.origin_w[c];
      direction.mutable_at(i, c) = a.anchor.direction_w[c];
    }
    for (py::ssize_t d = 0; d < z; ++d)
      latent.mutable_at(i, d) = d < static_cast<py::ssize_t>(a.latent.size())
                                    ? a.latent[static_cast<std::size_t>(d)]
                                    : 0.0f;
  }
  py::dict arrived;
  arrived["node"] = node;
  arrived["modality"] = modality;
  arrived["t_capture_s"] = t_capture;
  arrived["latent"] = latent;
  arrived["anchor_kind"] = kind;
  arrived["anchor_origin"] = origin;
  arrived["anchor_direction"] = direction;
  py::dict estimates;
  for (const auto& [method, p] : *v.estimated) estimates[py::str(method)] = Vec(p);
  py::dict obs;
  obs["k"] = v.k;
  obs["t_s"] = v.t_s;
  obs["arrivals"] = arrived;
  obs["estimates"] = estimates;
  obs["base_station"] = Vec(v.scorer->downlink().channel().config().position_m);
  return obs;
}

py::dict Stepper::Info(const sim::WindowView& v) const {
  const Eigen::Vector3d& bs = v.scorer->downlink().channel().config().position_m;
  py::dict rates;
  for (const std::string& method : v.edge->SteeredMethods()) {
    const auto it = v.estimated->find(method);
    const double gain = it == v.estimated->end() ? 0.0 : GainTowards(*v.scorer, it->second - bs);
    rates[py::str(method)] = channel::RateBpsHz(snr_db_, gain);
  }
  rates["perfect"] = channel::RateBpsHz(snr_db_, GainTowards(*v.scorer, *v.truth_m - bs));
  py::dict info;
  info["k"] = v.k;
  info["t_s"] = v.t_s;
  info["truth"] = Vec(*v.truth_m);
  info["rates"] = rates;
  return info;
}

double Stepper::ActionGain(const py::object& action) const {
  const sim::WindowView& v = *view_;
  const Eigen::Vector3d& bs = v.scorer->downlink().channel().config().position_m;
  if (action.is_none()) {
    const auto it = v.estimated->find(steer_by_);
    return it == v.estimated->end() ? 0.0 : GainTowards(*v.scorer, it->second - bs);
  }
  const auto d = py::module_::import("numpy")
                     .attr("asarray")(action, "float64")
                     .attr("reshape")(-1)
                     .cast<py::array_t<double>>();
  if (d.size() != 3) throw py::value_error("the action is a direction (3 numbers) or None");
  const Eigen::Vector3d u(d.at(0), d.at(1), d.at(2));
  if (!u.allFinite() || u.norm() == 0.0)
    throw py::value_error("the action's direction must be finite and not zero");
  return GainTowards(*v.scorer, u);
}

}  // namespace

void BindEnvironment(py::module_& m) {
  py::class_<Stepper>(m, "Stepper")
      .def(py::init([](const std::string& path, const std::string& document,
                       const std::vector<std::string>& overrides, const std::string& out_dir,
                       double snr_db, const std::string& steer_by, bool quiet,
                       const py::dict& methods) {
             return std::make_unique<Stepper>(ScenarioSource{path, document, overrides}, out_dir,
                                              snr_db, steer_by, quiet, methods);
           }),
           py::arg("path"), py::arg("document"), py::arg("overrides"), py::arg("out_dir"),
           py::arg("snr_db"), py::arg("steer_by"), py::arg("quiet"), py::arg("methods"))
      .def("reset", &Stepper::Reset)
      .def("step", &Stepper::Step, py::arg("action"))
      .def("close", &Stepper::Stop)
      .def_property_readonly("info", &Stepper::info);
}

}  // namespace uavsim::python
