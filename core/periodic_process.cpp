#include "core/periodic_process.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace uavsim::core {
namespace {

std::string Describe(double value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

double CheckedRate(double rate_hz) {
  // Up to 1 GHz the period is at least 1 ns, so nominal times strictly increase.
  if (!(std::isfinite(rate_hz) && rate_hz > 0.0 && rate_hz <= 1e9)) {
    throw std::invalid_argument("PeriodicProcess: rate_hz (" + Describe(rate_hz) +
                                ") must be a finite value in (0, 1e9]");
  }
  return rate_hz;
}

SimTime CheckedPhase(double phase_s) {
  if (!(std::isfinite(phase_s) && phase_s >= 0.0 && phase_s <= ToSeconds(kTimeMax) / 2)) {
    throw std::invalid_argument("PeriodicProcess: phase_s (" + Describe(phase_s) +
                                ") must be a finite value in [0, 4.6e9]");
  }
  return Seconds(phase_s);
}

double CheckedJitter(double jitter_s) {
  if (!(std::isfinite(jitter_s) && jitter_s >= 0.0)) {
    throw std::invalid_argument("PeriodicProcess: jitter_s (" + Describe(jitter_s) +
                                ") must be a finite value >= 0");
  }
  return jitter_s;
}

}  // namespace

PeriodicProcess::PeriodicProcess(double rate_hz, double phase_s, Callback callback)
    : PeriodicProcess(rate_hz, phase_s, 0.0, RngStream(0), std::move(callback)) {}

PeriodicProcess::PeriodicProcess(double rate_hz, double phase_s, double jitter_s,
                                 const RngStream& rng, Callback callback)
    : rate_hz_(CheckedRate(rate_hz)),
      phase_ns_(CheckedPhase(phase_s)),
      jitter_s_(CheckedJitter(jitter_s)),
      jitter_key_(rng.key()),
      callback_(std::move(callback)) {
  if (!callback_) throw std::invalid_argument("PeriodicProcess: the callback is empty");
}

PeriodicProcess::~PeriodicProcess() { Stop(); }

SimTime PeriodicProcess::NominalTime(std::int64_t k) const {
  // long double keeps k * 1e9 exact up to k ~ 1.8e10 on x86-64, so the
  // rounding is that of the exact quotient; a double would be exact only up
  // to k ~ 9e6.
  const long double offset_ns =
      std::round(static_cast<long double>(k) * 1e9L / static_cast<long double>(rate_hz_));
  const long double t_ns = static_cast<long double>(phase_ns_) + offset_ns;
  if (t_ns >= static_cast<long double>(kTimeMax)) return kTimeMax;
  return static_cast<SimTime>(t_ns);
}

std::int64_t PeriodicProcess::FirstTickAtOrAfter(SimTime t_ns) const {
  if (t_ns <= phase_ns_) return 0;
  // An estimate from the inverse of NominalTime, then corrected exactly.
  const long double estimate = std::ceil(static_cast<long double>(t_ns - phase_ns_) *
                                         static_cast<long double>(rate_hz_) / 1e9L);
  std::int64_t k = estimate >= static_cast<long double>(INT64_MAX - 1)
                       ? INT64_MAX - 1
                       : static_cast<std::int64_t>(estimate);
  while (k > 0 && NominalTime(k - 1) >= t_ns) --k;
  while (NominalTime(k) < t_ns) ++k;
  return k;
}

void PeriodicProcess::Start(Simulator& sim, SimTime t_start_ns, SimTime t_stop_ns) {
  if (t_start_ns < sim.Now()) {
    throw std::invalid_argument("PeriodicProcess::Start: t_start (" + std::to_string(t_start_ns) +
                                " ns) is before Now() = " + std::to_string(sim.Now()) + " ns");
  }
  if (t_stop_ns < t_start_ns) {
    throw std::invalid_argument("PeriodicProcess::Start: t_stop (" + std::to_string(t_stop_ns) +
                                " ns) is before t_start (" + std::to_string(t_start_ns) + " ns)");
  }
  Stop();
  sim_ = &sim;
  t_start_ns_ = t_start_ns;
  t_stop_ns_ = t_stop_ns;
  next_tick_ = FirstTickAtOrAfter(t_start_ns);
  last_delivered_ns_ = t_start_ns;
  ScheduleNext();
}

void PeriodicProcess::Stop() {
  if (pending_.valid()) sim_->Cancel(pending_);
  pending_ = EventId();
}

void PeriodicProcess::ScheduleNext() {
  const SimTime nominal_ns = NominalTime(next_tick_);
  if (nominal_ns >= t_stop_ns_) {
    pending_ = EventId();
    return;
  }
  pending_time_ns_ = JitteredTime(next_tick_, nominal_ns);
  pending_ = sim_->ScheduleAt(pending_time_ns_, [this] { Fire(); });
}

void PeriodicProcess::Fire() {
  const std::int64_t k = next_tick_++;
  const SimTime t_ns = sim_->Now();
  last_delivered_ns_ = t_ns;
  pending_ = EventId();
  // The next tick is scheduled first, so that Stop() inside the callback
  // cancels it.
  ScheduleNext();
  callback_(k, t_ns);
}

std::optional<SimTime> PeriodicProcess::delivery_after_next() const {
  if (!running()) return std::nullopt;
  const SimTime nominal_ns = NominalTime(next_tick_ + 1);
  if (nominal_ns >= t_stop_ns_) return std::nullopt;
  // As ScheduleNext will compute it once the pending tick is delivered.
  return JitteredTime(next_tick_ + 1, nominal_ns, pending_time_ns_);
}

SimTime PeriodicProcess::JitteredTime(std::int64_t k, SimTime nominal_ns) const {
  return JitteredTime(k, nominal_ns, last_delivered_ns_);
}

SimTime PeriodicProcess::JitteredTime(std::int64_t k, SimTime nominal_ns,
                                      SimTime last_delivered_ns) const {
  const SimTime lower_ns = std::max(last_delivered_ns, t_start_ns_);
  const SimTime upper_ns = t_stop_ns_ - 1;  // >= nominal_ns >= t_start_ns_ by construction
  long double t_ns = static_cast<long double>(nominal_ns);
  if (jitter_s_ > 0.0) {
    // A stream per tick, keyed by k, so that e_k does not depend on which
    // ticks were drawn before it.
    RngStream tick_rng(Mix64(jitter_key_ ^ Mix64(static_cast<std::uint64_t>(k))));
    t_ns += std::round(static_cast<long double>(jitter_s_) * 1e9L * tick_rng.Normal());
  }
  if (!(t_ns > static_cast<long double>(lower_ns))) return lower_ns;
  if (t_ns > static_cast<long double>(upper_ns)) return upper_ns;
  return static_cast<SimTime>(t_ns);
}

}  // namespace uavsim::core
