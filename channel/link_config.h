// An uplink's parameters: serialization at bandwidth_mbps, a fixed latency,
// jitter, a drop-tail buffer, a loss model, and (when carrier_ghz is set) rain
// attenuation of a mmWave link. Scheduled outages take the link down.
#pragma once

#include <optional>
#include <vector>

namespace uavsim::channel {

enum class JitterType { kNone, kNormal, kUniform, kPareto };
enum class LossType { kNone, kBernoulli, kGilbertElliott };

struct JitterConfig {
  JitterType type = JitterType::kNone;
  double std_ms = 0.0;    // normal (truncated at zero extra delay)
  double max_ms = 0.0;    // uniform on [0, max_ms]
  double scale_ms = 1.0;  // pareto: extra delay >= 0 with P(X > x) = (scale / (scale + x))^shape
  double shape = 2.5;
};

struct LossConfig {
  LossType type = LossType::kBernoulli;
  double p = 0.0;          // bernoulli: loss probability; gilbert_elliott: P(good -> bad)
  double r = 0.5;          // gilbert_elliott: P(bad -> good)
  double loss_good = 0.0;  // gilbert_elliott: loss probability in the good state
  double loss_bad = 1.0;   // gilbert_elliott: loss probability in the bad state
};

struct OutageConfig {
  double from_s = 0.0;
  double to_s = 0.0;
};

struct LinkConfig {
  double bandwidth_mbps = 20.0;
  double latency_ms = 5.0;
  JitterConfig jitter;
  LossConfig loss;
  int mtu_bytes = 1500;
  int buffer_packets = 1000;
  std::optional<double> carrier_ghz;  // unset: rain does not affect this link
  std::vector<OutageConfig> outages;
};

template <class V>
void Visit(V& v, JitterConfig& c);
template <class V>
void Visit(V& v, LossConfig& c);
template <class V>
void Visit(V& v, OutageConfig& c);
template <class V>
void Visit(V& v, LinkConfig& c);

}  // namespace uavsim::channel
