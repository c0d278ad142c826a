#include "channel/edge_receiver.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace uavsim::channel {

namespace {

double PercentileOfSorted(const std::vector<double>& v, double q) {
  const double h = static_cast<double>(v.size() - 1) * q;
  const auto lo = static_cast<std::size_t>(std::floor(h));
  if (lo + 1 >= v.size()) return v[lo];
  return v[lo] + (h - static_cast<double>(lo)) * (v[lo + 1] - v[lo]);
}

}  // namespace

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) throw std::invalid_argument("Percentile: no values");
  if (!(q >= 0.0 && q <= 1.0)) throw std::invalid_argument("Percentile: q must be in [0, 1]");
  std::sort(values.begin(), values.end());
  return PercentileOfSorted(values, q);
}

EdgeReceiver::EdgeReceiver(double window_s, double late_allowance_s) {
  if (!std::isfinite(window_s) || window_s <= 0.0 || window_s > 1e6)
    throw std::invalid_argument("EdgeReceiver: window_s must be in (0, 1e6] s");
  if (!std::isfinite(late_allowance_s) || late_allowance_s < 0.0 || late_allowance_s > 1e6)
    throw std::invalid_argument("EdgeReceiver: late_allowance_s must be in [0, 1e6] s");
  window_ns_ = core::Seconds(window_s);
  allowance_ns_ = core::Seconds(late_allowance_s);
  if (window_ns_ <= 0) throw std::invalid_argument("EdgeReceiver: window_s below 1 ns");
}

core::SimTime EdgeReceiver::DeadlineNs(core::SimTime t_capture_ns) const {
  if (t_capture_ns < 0) throw std::invalid_argument("EdgeReceiver: negative capture time");
  return (t_capture_ns / window_ns_ + 1) * window_ns_ + allowance_ns_;
}

const char* FateName(Fate f) {
  switch (f) {
    case Fate::kDelivered:
      return "delivered";
    case Fate::kLate:
      return "late";
    case Fate::kLost:
      return "lost";
    default:
      return "in_flight";
  }
}

void EdgeReceiver::OnSent(const Message& message) {
  ++counts_[Index(message.modality)].sent;
  in_flight_[{message.node, message.sequence}] = log_.size();
  MessageRecord r;
  r.node = message.node;
  r.modality = message.modality;
  r.sequence = message.sequence;
  r.t_capture_ns = message.t_capture_ns;
  r.payload_bytes = message.payload_bytes;
  log_.push_back(r);
}

MessageRecord* EdgeReceiver::Resolve(const Message& message) {
  const auto it = in_flight_.find({message.node, message.sequence});
  if (it == in_flight_.end()) return nullptr;
  MessageRecord* r = &log_[it->second];
  in_flight_.erase(it);
  return r;
}

bool EdgeReceiver::OnArrival(const Message& message, core::SimTime t_arrival_ns) {
  ReceptionCounts& c = counts_[Index(message.modality)];
  if (c.in_flight() == 0)
    throw std::logic_error(std::string("EdgeReceiver: a ") + ModalityName(message.modality) +
                           " message arrived that was not reported sent");
  latencies_ns_[Index(message.modality)].push_back(t_arrival_ns - message.t_capture_ns);
  const bool late = IsLate(message.t_capture_ns, t_arrival_ns);
  ++(late ? c.late : c.delivered);
  if (MessageRecord* r = Resolve(message)) {
    r->fate = late ? Fate::kLate : Fate::kDelivered;
    r->t_arrival_ns = t_arrival_ns;
  }
  return !late;
}

void EdgeReceiver::OnLost(const Message& message) {
  ReceptionCounts& c = counts_[Index(message.modality)];
  if (c.in_flight() == 0)
    throw std::logic_error(std::string("EdgeReceiver: a ") + ModalityName(message.modality) +
                           " message was lost that was not reported sent");
  ++c.lost;
  if (MessageRecord* r = Resolve(message)) r->fate = Fate::kLost;
}

LatencySummary EdgeReceiver::Latency(Modality m) const {
  const auto& ns = latencies_ns_[Index(m)];
  LatencySummary s;
  s.count = ns.size();
  if (ns.empty()) return s;
  std::vector<double> v(ns.size());
  double sum = 0.0;
  for (std::size_t i = 0; i < ns.size(); ++i) sum += v[i] = core::ToSeconds(ns[i]);
  s.mean_s = sum / static_cast<double>(v.size());
  std::sort(v.begin(), v.end());
  s.p50_s = PercentileOfSorted(v, 0.50);
  s.p95_s = PercentileOfSorted(v, 0.95);
  s.p99_s = PercentileOfSorted(v, 0.99);
  s.max_s = v.back();
  return s;
}

void EdgeReceiver::WriteMetrics(core::Json& modalities) const {
  for (int i = 0; i < kModalityCount; ++i) {
    const auto m = static_cast<Modality>(i);
    const ReceptionCounts& c = Counts(m);
    const LatencySummary l = Latency(m);
    core::Json& out = modalities[ModalityName(m)];
    out["packets_sent"] = c.sent;
    out["packets_delivered"] = c.delivered;
    out["packets_late"] = c.late;
    out["packets_lost"] = c.lost;
    out["packets_in_flight"] = c.in_flight();
    auto stat = [&l](double x) { return l.count ? core::Json(x) : core::Json(nullptr); };
    out["latency_s"] = {{"count", l.count},     {"mean", stat(l.mean_s)}, {"p50", stat(l.p50_s)},
                        {"p95", stat(l.p95_s)}, {"p99", stat(l.p99_s)},   {"max", stat(l.max_s)}};
  }
}

}  // namespace uavsim::channel
