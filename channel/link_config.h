// An uplink's parameters (one entry of the scenario's "links" map): the
// serialization rate, a fixed latency, jitter, a drop-tail buffer, a loss
// model, a radio link budget whose packet error rate rises when rain
// attenuates a mmWave carrier, and scheduled outages of the link or of nodes.
// channel::Uplink (uplink.h) implements the model; the formulas are there.
//
// Every key has a default and a validated range; reading is strict (see
// core/json_io.h): core::FromJson throws core::ConfigError naming the file
// and the JSON pointer.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/rain_attenuation.h"

namespace uavsim::channel {

enum class JitterType { kNone, kNormal, kUniform, kPareto };
enum class LossType { kNone, kBernoulli, kGilbertElliott };
// Uncoded modulation of the SNR -> bit error rate mapping (uplink.h).
enum class Modulation { kBpsk, kQpsk, kQam16, kQam64, kQam256 };

// Extra one-way delay J added to latency_ms, drawn independently for every
// fragment. The delay after serialization, latency + J, is never negative.
struct JitterConfig {
  JitterType type = JitterType::kNone;
  // normal: J ~ N(0, std_ms^2) truncated to latency + J >= 0 (redrawn, not
  // clamped), so J has zero mean while std_ms << latency_ms.
  double std_ms = 0.0;
  double max_ms = 0.0;    // uniform: J on [0, max_ms]
  double scale_ms = 1.0;  // pareto (Lomax): J >= 0 with P(J > x) = (scale / (scale + x))^shape
  double shape = 2.5;
};

// Applied to every fragment that goes on the air while the link is up.
struct LossConfig {
  LossType type = LossType::kBernoulli;
  double p = 0.0;          // bernoulli: loss probability; gilbert_elliott: P(good -> bad)
  double r = 0.5;          // gilbert_elliott: P(bad -> good)
  double loss_good = 0.0;  // gilbert_elliott: loss probability in the good state
  double loss_bad = 1.0;   // gilbert_elliott: loss probability in the bad state
};

// The link, or only the listed nodes, is down on [from_s, to_s).
//  - link (nodes empty): a fragment whose serialization interval
//    [t_start, t_start + bytes * 8 / bandwidth) overlaps the outage is lost;
//    fragments already past the transmitter are not.
//  - nodes: messages the listed nodes send at t in [from_s, to_s) are lost at
//    the node and never enter the link's buffer (the node's radio is down).
// Node ids must be nodes that use this link (CheckOutageNodes).
struct OutageConfig {
  double from_s = 0.0;
  double to_s = 0.0;
  std::vector<std::string> nodes;  // empty: the whole link
};

struct LinkConfig {
  double bandwidth_mbps = 20.0;  // serialization: bytes * 8 / bandwidth
  double latency_ms = 5.0;       // fixed one-way delay after serialization
  JitterConfig jitter;
  LossConfig loss;
  // Largest fragment on the wire, fragment header included. A message of B
  // bytes travels as ceil(B / (mtu_bytes - fragment_header_bytes)) fragments.
  int mtu_bytes = 1500;
  int fragment_header_bytes = 28;  // per fragment: IPv4 (20) + UDP (8)
  // Drop-tail FIFO capacity, counted in fragments waiting for the
  // transmitter; the fragment being serialized is not counted (ns-3's
  // DropTailQueue habit).
  int buffer_packets = 1000;

  // Radio link budget. snr_db is the clear-sky Es/N0 at the edge receiver;
  // rain lowers it by gamma_R(carrier, rain) * path_length_m (uplink.h).
  double snr_db = 25.0;
  Modulation modulation = Modulation::kQam16;
  double coding_gain_db = 0.0;  // added to the SNR before the uncoded BER curve
  // Carrier of a mmWave link, GHz in [1, 1000] (ITU-R P.838-3's range);
  // unset: rain does not affect this link.
  std::optional<double> carrier_ghz;
  double path_length_m = 1000.0;  // rain-filled length of the path (uniform rain)
  core::Polarization polarization = core::Polarization::kHorizontal;
  double path_elevation_deg = 0.0;

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

// Cross-check for the scenario loader: every node named in an outage of
// `link` must be in `node_ids` (the ids of the nodes whose uplink is this
// link). Throws core::ConfigError at
// `link_pointer`/outages/<i>/nodes/<j>, e.g.
//   s.json: /links/default/outages/0/nodes/1: node "cam9" does not use this
//   link (its nodes: "cam1", "lidar1")
void CheckOutageNodes(const LinkConfig& link, const std::vector<std::string>& node_ids,
                      const std::string& file, const std::string& link_pointer);

}  // namespace uavsim::channel
