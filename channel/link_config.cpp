#include "channel/link_config.h"

#include <algorithm>

#include "core/json_io.h"

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
  v("nodes", c.nodes);
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
  v("fragment_header_bytes", c.fragment_header_bytes, Rule::Range(0, 1024));
  v.Check(
      c.fragment_header_bytes < c.mtu_bytes, "fragment_header_bytes",
      "fragment_header_bytes must be less than mtu_bytes (" + std::to_string(c.mtu_bytes) + ")");
  v("buffer_packets", c.buffer_packets, Rule::Range(1, 10000000));
  v("snr_db", c.snr_db, Rule::Range(-50.0, 100.0));
  v.Enum("modulation", c.modulation,
         {{"bpsk", Modulation::kBpsk},
          {"qpsk", Modulation::kQpsk},
          {"16qam", Modulation::kQam16},
          {"64qam", Modulation::kQam64},
          {"256qam", Modulation::kQam256}});
  v("coding_gain_db", c.coding_gain_db, Rule::Range(0.0, 20.0));
  v("carrier_ghz", c.carrier_ghz, Rule::Range(1.0, 1000.0));
  v("path_length_m", c.path_length_m, Rule::NonNegative(100000.0));
  v.Enum("polarization", c.polarization, core::PolarizationNames());
  v("path_elevation_deg", c.path_elevation_deg, Rule::Range(0.0, 90.0));
  v.Array("outages", c.outages, 0, 10000);
}
UAVSIM_INSTANTIATE_VISIT(LinkConfig);

void CheckOutageNodes(const LinkConfig& link, const std::vector<std::string>& node_ids,
                      const std::string& file, const std::string& link_pointer) {
  for (std::size_t i = 0; i < link.outages.size(); ++i) {
    const auto& nodes = link.outages[i].nodes;
    for (std::size_t j = 0; j < nodes.size(); ++j) {
      if (std::find(node_ids.begin(), node_ids.end(), nodes[j]) != node_ids.end()) continue;
      std::string known;
      for (const auto& id : node_ids) known += (known.empty() ? "\"" : ", \"") + id + "\"";
      throw core::ConfigError(
          file, link_pointer + "/outages/" + std::to_string(i) + "/nodes/" + std::to_string(j),
          "node " + core::DescribeValue(core::Json(nodes[j])) + " does not use this link (" +
              (known.empty() ? std::string("no node uses it") : "its nodes: " + known) + ")");
    }
  }
}

}  // namespace uavsim::channel
