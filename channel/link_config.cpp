#include "channel/link_config.h"
#include "sim/core/json_io.h"

namespace uavsim::channel {

using core::Rule;

template <class V>
void Visit(V& v, JitterConfig& c) {
  v.Enum("type", c.type,
         {{"none", JitterType::kNone},
          {"normal", JitterType::kNormal},
          {"uniform", JitterType::kUniform},
          {"pareto", JitterType::kPareto}});
  switch (c.type) {
    case JitterType::kNone:
      break;
    case JitterType::kNormal:
      v("std_ms", c.std_ms, Rule::NonNegative(10000.0));
      break;
    case JitterType::kUniform:
      v("max_ms", c.max_ms, Rule::NonNegative(10000.0));
      break;
    case JitterType::kPareto:
      v("scale_ms", c.scale_ms, Rule::Positive(10000.0));
      v("shape", c.shape, Rule{0.0, 100.0, true, false});
      break;
  }
}
UAVSIM_INSTANTIATE_VISIT(JitterConfig);

template <class V>
void Visit(V& v, LossConfig& c) {
  v.Enum("type", c.type,
         {{"none", LossType::kNone},
          {"bernoulli", LossType::kBernoulli},
          {"gilbert_elliott", LossType::kGilbertElliott}});
  switch (c.type) {
    case LossType::kNone:
      break;
    case LossType::kBernoulli:
      v("p", c.p, Rule::Probability());
      break;
    case LossType::kGilbertElliott:
      v("p", c.p, Rule::Probability());
      v("r", c.r, Rule{0.0, 1.0, true, false});
      v("loss_good", c.loss_good, Rule::Probability());
      v("loss_bad", c.loss_bad, Rule::Probability());
      break;
  }
}
UAVSIM_INSTANTIATE_VISIT(LossConfig);

template <class V>
void Visit(V& v, OutageConfig& c) {
  v("from_s", c.from_s, Rule::NonNegative(1e7));
  v("to_s", c.to_s, Rule::NonNegative(1e7));
  v.Check(c.from_s < c.to_s, "to_s",
          "to_s must be after from_s (" + core::FormatNumber(c.from_s) + ")");
}
UAVSIM_INSTANTIATE_VISIT(OutageConfig);

template <class V>
void Visit(V& v, LinkConfig& c) {
  v("bandwidth_mbps", c.bandwidth_mbps, Rule::Positive(1e6));
  v("latency_ms", c.latency_ms, Rule::NonNegative(1e5));
  v.Object("jitter", c.jitter);
  v.Object("loss", c.loss);
  v("mtu_bytes", c.mtu_bytes, Rule::Range(64, 65535));
  v("buffer_packets", c.buffer_packets, Rule::Range(1, 10000000));
  v("carrier_ghz", c.carrier_ghz, Rule{0.1, 1000.0, false, false});
  v.Array("outages", c.outages, 0, 10000);
}
UAVSIM_INSTANTIATE_VISIT(LinkConfig);

}  // namespace uavsim::channel
