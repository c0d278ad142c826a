// A callback fired at a fixed rate on a Simulator: a sensor's frame clock.
//
// Tick k (k = 0, 1, 2, ...) has the nominal time
//   t_k = phase + round(k * 1e9 / rate_hz)  [ns],
// computed from the integer k, never by adding periods, so there is no drift:
// 30, 10 and 15 Hz give exactly 1800, 600 and 900 ticks in [0, 60 s). The grid
// is absolute (tick 0 is at `phase_s` after time 0) and does not move with
// Start's t_start, so stopping and restarting keeps the same tick indices.
//
// Start(sim, t_start, t_stop) fires exactly the ticks with
// t_start <= t_k < t_stop: the start is inclusive, the stop exclusive.
//
// Clock jitter: with jitter_s > 0, tick k is delivered at t_k + e_k, where
// e_k ~ N(0, jitter_s^2) (rounded to the nanosecond) is drawn afresh for every
// tick, so errors do not accumulate. The delivered time is then clamped to be
// no earlier than the previous delivered tick (ticks stay in order) nor than
// t_start, and no later than t_stop - 1 ns (each nominal tick is delivered
// inside the window). The clamps only touch ticks within a few jitter_s of
// their neighbours or of the window's ends.
//
// Determinism: e_k depends only on the key of the RngStream passed in and on
// k, not on how many ticks were drawn before, so a tick's delivered time does
// not change with t_start or with a restart. Nothing else is random.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>

#include "core/rng.h"
#include "core/simulator.h"
#include "core/time.h"

namespace uavsim::core {

class PeriodicProcess {
 public:
  // Receives the tick index k and the delivered (possibly jittered) time,
  // which equals sim.Now() during the call.
  using Callback = std::function<void(std::int64_t tick, SimTime t_ns)>;

  // A clock without jitter. Throws std::invalid_argument unless rate_hz is
  // finite and in (0, 1e9] and phase_s is finite and >= 0, or if the callback
  // is empty.
  PeriodicProcess(double rate_hz, double phase_s, Callback callback);

  // A clock with Gaussian timing jitter of standard deviation jitter_s, drawn
  // from `rng` (only its key is used; see Determinism above). jitter_s == 0
  // gives the nominal times. Throws std::invalid_argument as above, and unless
  // jitter_s is finite and >= 0.
  PeriodicProcess(double rate_hz, double phase_s, double jitter_s, const RngStream& rng,
                  Callback callback);

  // Stops the process (cancels its pending tick). The Simulator it was started
  // on must still exist, or the process must have been stopped before.
  ~PeriodicProcess();
  PeriodicProcess(const PeriodicProcess&) = delete;
  PeriodicProcess& operator=(const PeriodicProcess&) = delete;

  // Schedules the ticks with t_start_ns <= t_k < t_stop_ns on `sim`, one at a
  // time (each tick schedules the next before calling the callback). Restarts
  // the process if it is running. Throws std::invalid_argument if
  // t_start_ns < sim.Now() or t_stop_ns < t_start_ns.
  void Start(Simulator& sim, SimTime t_start_ns, SimTime t_stop_ns = kTimeMax);

  // Cancels the pending tick, if any. Safe to call from inside the callback
  // (no further tick is delivered), when stopped, and more than once.
  void Stop();

  // True from Start until Stop or until the last tick of the window has been
  // delivered (false already inside that last tick's callback).
  bool running() const { return pending_.valid(); }

  // When the next tick will be delivered (jitter included), if one is
  // scheduled. Inside the callback this is already the following tick, so
  // a component may start that tick's work ahead of time.
  std::optional<SimTime> next_delivery() const {
    return running() ? std::optional<SimTime>(pending_time_ns_) : std::nullopt;
  }

  // When the tick after the next one will be delivered (jitter included),
  // if both fall in the window: what next_delivery() will say once the next
  // tick is delivered, so a component may start two ticks' work ahead.
  std::optional<SimTime> delivery_after_next() const;
  // The nominal time of tick k >= 0: phase + round(k * 1e9 / rate_hz) ns,
  // saturating at kTimeMax.
  SimTime NominalTime(std::int64_t k) const;

  double rate_hz() const { return rate_hz_; }
  double jitter_s() const { return jitter_s_; }

 private:
  void ScheduleNext();
  void Fire();
  std::int64_t FirstTickAtOrAfter(SimTime t_ns) const;
  SimTime JitteredTime(std::int64_t k, SimTime nominal_ns) const;
  SimTime JitteredTime(std::int64_t k, SimTime nominal_ns, SimTime last_delivered_ns) const;

  double rate_hz_;
  SimTime phase_ns_;
  double jitter_s_;
  std::uint64_t jitter_key_;
  Callback callback_;

  Simulator* sim_ = nullptr;
  SimTime t_start_ns_ = 0;
  SimTime t_stop_ns_ = 0;
  std::int64_t next_tick_ = 0;
  SimTime last_delivered_ns_ = 0;
  EventId pending_;  // the scheduled next tick; default when none
  SimTime pending_time_ns_ = 0;
};

}  // namespace uavsim::core
