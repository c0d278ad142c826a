#include "channel/uplink.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "core/json_io.h"
#include "core/rain_attenuation.h"

namespace uavsim::channel {
namespace {

using core::SimTime;

// Keeps a Pareto tail from overflowing the clock.
constexpr double kMaxJitterNs = 1e18;

double Q(double x) { return 0.5 * std::erfc(x / std::sqrt(2.0)); }

// Re-reads the config through its own Visit, so a hand-built LinkConfig meets
// exactly the rules a scenario file does.
LinkConfig Validated(const LinkConfig& config) {
  LinkConfig out;
  core::FromJson(core::ToJson(config), "uplink config", "", out);
  return out;
}

}  // namespace

const char* LossCauseName(LossCause cause) {
  switch (cause) {
    case LossCause::kNodeDown:
      return "node_down";
    case LossCause::kBufferFull:
      return "buffer_full";
    case LossCause::kLinkDown:
      return "link_down";
    case LossCause::kChannel:
      return "channel";
    case LossCause::kBitErrors:
      return "bit_errors";
  }
  return "unknown";
}

double BitErrorRate(Modulation modulation, double snr_db) {
  const double gamma = std::pow(10.0, snr_db / 10.0);
  double m = 4.0;
  switch (modulation) {
    case Modulation::kBpsk:
      return std::min(0.5, Q(std::sqrt(2.0 * gamma)));
    case Modulation::kQpsk:
      m = 4.0;
      break;
    case Modulation::kQam16:
      m = 16.0;
      break;
    case Modulation::kQam64:
      m = 64.0;
      break;
    case Modulation::kQam256:
      m = 256.0;
      break;
  }
  const double ber =
      4.0 / std::log2(m) * (1.0 - 1.0 / std::sqrt(m)) * Q(std::sqrt(3.0 * gamma / (m - 1.0)));
  return std::min(0.5, ber);
}

void Uplink::StartTimes::pop_front() {
  head_ = head_ + 1 == ring_.size() ? 0 : head_ + 1;
  --size_;
}

void Uplink::StartTimes::push_back(SimTime t) {
  if (size_ == ring_.size()) {
    std::vector<SimTime> grown(std::max<std::size_t>(64, 2 * ring_.size()));
    for (std::size_t i = 0; i < size_; ++i) grown[i] = ring_[(head_ + i) % ring_.size()];
    ring_ = std::move(grown);
    head_ = 0;
  }
  std::size_t tail = head_ + size_;
  if (tail >= ring_.size()) tail -= ring_.size();
  ring_[tail] = t;
  ++size_;
}

Uplink::Uplink(core::Simulator& sim, const LinkConfig& config, const core::WeatherConfig& weather,
               core::RngStream rng, std::vector<std::string> node_ids)
    : sim_(sim),
      config_(Validated(config)),
      loss_rng_(rng.Derive("loss")),
      bit_error_rng_(rng.Derive("bit_errors")),
      jitter_rng_(rng.Derive("jitter")),
      node_ids_(std::move(node_ids)) {
  latency_ns_ = core::Milliseconds(config_.latency_ms);
  full_ = Fragment(static_cast<std::uint32_t>(config_.mtu_bytes - config_.fragment_header_bytes),
                   static_cast<std::uint32_t>(config_.mtu_bytes),
                   static_cast<std::uint32_t>(config_.fragment_header_bytes));
  full_serialization_ns_ = SerializationNs(full_.last_wire_bytes);

  node_outages_.resize(node_ids_.size());
  for (const OutageConfig& o : config_.outages) {
    const Interval interval{core::Seconds(o.from_s), core::Seconds(o.to_s)};
    if (o.nodes.empty()) link_outages_.push_back(interval);
    for (const std::string& id : o.nodes) {
      const auto it = std::find(node_ids_.begin(), node_ids_.end(), id);
      if (it == node_ids_.end())
        throw std::invalid_argument("uplink: an outage names node \"" + id +
                                    "\", which is not among the node ids given");
      node_outages_[static_cast<std::size_t>(it - node_ids_.begin())].push_back(interval);
    }
  }
  // Merged, a fragment's wire interval overlaps at most the first outage
  // that ends after its start, which LinkDown can then find in O(1) amortised.
  std::sort(link_outages_.begin(), link_outages_.end(),
            [](const Interval& a, const Interval& b) { return a.from_ns < b.from_ns; });
  std::vector<Interval> merged;
  for (const Interval& i : link_outages_) {
    if (!merged.empty() && i.from_ns <= merged.back().to_ns)
      merged.back().to_ns = std::max(merged.back().to_ns, i.to_ns);
    else
      merged.push_back(i);
  }
  link_outages_ = std::move(merged);

  if (config_.loss.type == LossType::kGilbertElliott) {
    const double p_bad = config_.loss.p / (config_.loss.p + config_.loss.r);
    channel_bad_ = loss_rng_.Bernoulli(p_bad);
  }
  SetWeather(weather);
}

Uplink::~Uplink() {
  for (const InFlight& f : in_flight_) sim_.Cancel(f.arrival);
}

void Uplink::SetWeather(const core::WeatherConfig& weather) {
  if (!std::isfinite(weather.rain_mm_h) || weather.rain_mm_h < 0.0)
    throw std::invalid_argument("uplink: rain rate must be finite and >= 0 mm/h");
  rain_attenuation_db_ =
      config_.carrier_ghz
          ? core::RainSpecificAttenuationDbPerKm(*config_.carrier_ghz, weather.rain_mm_h,
                                                 config_.polarization, config_.path_elevation_deg) *
                config_.path_length_m / 1000.0
          : 0.0;
  snr_db_ = config_.snr_db + config_.coding_gain_db - rain_attenuation_db_;
  bit_error_rate_ = BitErrorRate(config_.modulation, snr_db_);
  log_bit_success_ = std::log1p(-bit_error_rate_);
  full_fragment_error_rate_ = FragmentErrorRate(full_.full_wire_bytes);
}

double Uplink::FragmentErrorRate(std::uint32_t wire_bytes) const {
  return -std::expm1(8.0 * wire_bytes * log_bit_success_);
}

SimTime Uplink::SerializationNs(std::uint32_t wire_bytes) const {
  return static_cast<SimTime>(std::llround(8000.0 * wire_bytes / config_.bandwidth_mbps));
}

void Uplink::Send(Message message) {
  if (message.payload_bytes == 0)
    throw std::invalid_argument("uplink: a message needs payload_bytes >= 1");
  if (!node_ids_.empty() && message.node >= node_ids_.size())
    throw std::invalid_argument("uplink: message from node index " + std::to_string(message.node) +
                                ", but only " + std::to_string(node_ids_.size()) +
                                " node ids were given");
  ++stats_.messages_sent;
  if (!node_outages_.empty()) {
    const SimTime now = sim_.Now();
    for (const Interval& i : node_outages_[message.node])
      if (i.from_ns <= now && now < i.to_ns) return Lose(message, LossCause::kNodeDown);
  }
  DoSend(std::move(message));
}

void Uplink::DoSend(Message&& message) {
  const SimTime now = sim_.Now();
  while (!waiting_.empty() && waiting_.front() <= now) waiting_.pop_front();
  const Fragmentation fragments =
      Fragment(message.payload_bytes, static_cast<std::uint32_t>(config_.mtu_bytes),
               static_cast<std::uint32_t>(config_.fragment_header_bytes));
  const auto buffer_limit = static_cast<std::size_t>(config_.buffer_packets);

  bool lost = false;
  LossCause cause = LossCause::kChannel;
  auto lose_fragment = [&](LossCause c) {
    ++stats_.fragments_lost_by_cause[static_cast<int>(c)];
    if (!lost) lost = true, cause = c;
  };
  SimTime arrival_ns = now;
  for (std::uint32_t i = 0; i < fragments.count; ++i) {
    const bool last = i + 1 == fragments.count;
    const std::uint32_t bytes = last ? fragments.last_wire_bytes : fragments.full_wire_bytes;
    ++stats_.fragments_sent;
    const SimTime start_ns = std::max(now, wire_free_ns_);
    if (start_ns > now) {
      if (waiting_.size() >= buffer_limit) {
        lose_fragment(LossCause::kBufferFull);
        continue;
      }
      waiting_.push_back(start_ns);
    }
    const SimTime end_ns = start_ns + (bytes == full_.full_wire_bytes ? full_serialization_ns_
                                                                      : SerializationNs(bytes));
    wire_free_ns_ = end_ns;
    if (LinkDown(start_ns, end_ns)) {
      lose_fragment(LossCause::kLinkDown);
      continue;
    }
    if (ChannelLoses()) {
      lose_fragment(LossCause::kChannel);
      continue;
    }
    if (lost) continue;
    if (BitErrorsLose(bytes)) {
      lose_fragment(LossCause::kBitErrors);
      continue;
    }
    arrival_ns = std::max(arrival_ns, end_ns + latency_ns_ + DrawJitterNs());
  }
  if (lost) return Lose(message, cause);

  std::uint32_t slot;
  if (free_slots_.empty()) {
    slot = static_cast<std::uint32_t>(in_flight_.size());
    in_flight_.emplace_back();
  } else {
    slot = free_slots_.back();
    free_slots_.pop_back();
  }
  in_flight_[slot].message = std::move(message);
  in_flight_[slot].arrival = sim_.ScheduleAt(arrival_ns, [this, slot] { Deliver(slot); });
}

bool Uplink::LinkDown(SimTime start_ns, SimTime end_ns) {
  // Wire start times never decrease, so outages that ended are passed for good.
  while (next_link_outage_ < link_outages_.size() &&
         link_outages_[next_link_outage_].to_ns <= start_ns)
    ++next_link_outage_;
  if (next_link_outage_ == link_outages_.size()) return false;
  const Interval& o = link_outages_[next_link_outage_];
  // A zero-length serialization still counts as on the wire at its start.
  return o.from_ns < std::max(end_ns, start_ns + 1);
}

bool Uplink::ChannelLoses() {
  const LossConfig& l = config_.loss;
  auto draw = [this](double p) { return p >= 1.0 || (p > 0.0 && loss_rng_.Bernoulli(p)); };
  switch (l.type) {
    case LossType::kNone:
      return false;
    case LossType::kBernoulli:
      return draw(l.p);
    case LossType::kGilbertElliott:
      channel_bad_ = channel_bad_ ? !draw(l.r) : draw(l.p);
      return draw(channel_bad_ ? l.loss_bad : l.loss_good);
  }
  return false;
}

bool Uplink::BitErrorsLose(std::uint32_t wire_bytes) {
  const double per = wire_bytes == full_.full_wire_bytes ? full_fragment_error_rate_
                                                         : FragmentErrorRate(wire_bytes);
  return per >= 1.0 || (per > 0.0 && bit_error_rng_.Bernoulli(per));
}

SimTime Uplink::DrawJitterNs() {
  const JitterConfig& j = config_.jitter;
  double jitter_ns = 0.0;
  switch (j.type) {
    case JitterType::kNone:
      return 0;
    case JitterType::kNormal: {
      if (j.std_ms == 0.0) return 0;
      const double sigma_ns = j.std_ms * 1e6;
      const auto floor_ns = static_cast<double>(-latency_ns_);
      // Rejection keeps the exact truncated law; with latency >= 0 at least
      // half the draws are accepted.
      do jitter_ns = jitter_rng_.Normal(0.0, sigma_ns);
      while (jitter_ns < floor_ns);
      break;
    }
    case JitterType::kUniform:
      if (j.max_ms == 0.0) return 0;
      jitter_ns = jitter_rng_.Uniform(0.0, j.max_ms * 1e6);
      break;
    case JitterType::kPareto:
      jitter_ns = (jitter_rng_.Pareto(j.scale_ms, j.shape) - j.scale_ms) * 1e6;
      break;
  }
  // Rounding must not undo the truncation: latency + J >= 0 in nanoseconds.
  return std::max(-latency_ns_,
                  static_cast<SimTime>(std::llround(std::min(jitter_ns, kMaxJitterNs))));
}

void Uplink::Lose(const Message& message, LossCause cause) {
  ++stats_.messages_lost;
  ++stats_.messages_lost_by_cause[static_cast<int>(cause)];
  if (on_loss_) on_loss_(message, cause);
}

void Uplink::Deliver(std::uint32_t slot) {
  // Moved out first: the callback may Send, which may grow in_flight_.
  const Message message = std::move(in_flight_[slot].message);
  in_flight_[slot].arrival = core::EventId();
  free_slots_.push_back(slot);
  ++stats_.messages_delivered;
  if (on_arrival_) on_arrival_(message, sim_.Now());
}

}  // namespace uavsim::channel
