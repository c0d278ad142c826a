#include "channel/uplink.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "channel/packet.h"
#include "core/error.h"
#include "core/simulator.h"
#include "core/time.h"

using uavsim::channel::BitErrorRate;
using uavsim::channel::Fragment;
using uavsim::channel::JitterType;
using uavsim::channel::LinkConfig;
using uavsim::channel::LossCause;
using uavsim::channel::LossType;
using uavsim::channel::Message;
using uavsim::channel::Modality;
using uavsim::channel::Modulation;
using uavsim::channel::OutageConfig;
using uavsim::channel::Uplink;
using uavsim::core::Milliseconds;
using uavsim::core::RngStream;
using uavsim::core::Seconds;
using uavsim::core::SimTime;
using uavsim::core::Simulator;
using uavsim::core::WeatherConfig;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A link with no randomness at all: tests switch on one effect at a time.
// At 60 dB the bit error rate underflows to exactly 0.
LinkConfig QuietLink() {
  LinkConfig c;
  c.bandwidth_mbps = 20.0;
  c.latency_ms = 0.0;
  c.loss.type = LossType::kNone;
  c.snr_db = 60.0;
  return c;
}

struct Record {
  bool arrived = false;
  bool lost = false;
  LossCause cause = LossCause::kChannel;
  std::uint32_t node = 0;
  SimTime t_sent_ns = 0;
  SimTime t_arrival_ns = 0;
};

// One link on its own simulator; every message's fate is recorded by sequence.
struct Bench {
  Simulator sim;
  Uplink link;
  std::vector<Record> records;
  std::vector<std::uint64_t> arrival_order;

  explicit Bench(const LinkConfig& c, std::uint64_t seed = 7, double rain_mm_h = 0.0,
                 std::vector<std::string> node_ids = {})
      : link(sim, c, WeatherConfig{rain_mm_h, {}, 1.0}, RngStream(seed, "link/test"),
             std::move(node_ids)) {
    link.SetArrivalCallback([this](const Message& m, SimTime t) {
      Record& r = records.at(m.sequence);
      REQUIRE_FALSE(r.arrived);
      r.arrived = true;
      r.t_arrival_ns = t;
      arrival_order.push_back(m.sequence);
    });
    link.SetLossCallback([this](const Message& m, LossCause cause) {
      Record& r = records.at(m.sequence);
      r.lost = true;
      r.cause = cause;
    });
  }

  // Schedules message `records.size()` from `node` with `bytes` at t_ns.
  void SendAt(SimTime t_ns, std::uint32_t bytes, std::uint32_t node = 0) {
    const std::uint64_t seq = records.size();
    records.push_back(Record{});
    records.back().t_sent_ns = t_ns;
    records.back().node = node;
    sim.ScheduleAt(t_ns, [this, t_ns, bytes, node, seq] {
      Message m;
      m.node = node;
      m.modality = Modality::kRadar;
      m.sequence = seq;
      m.t_capture_ns = t_ns;
      m.payload_bytes = bytes;
      link.Send(std::move(m));
    });
  }

  std::size_t Lost() const {
    std::size_t n = 0;
    for (const Record& r : records) n += r.lost;
    return n;
  }
};

// The exact two-sided 99 % interval [lo, hi] of Binomial(n, p): the 0.5 % and
// 99.5 % quantiles, from the probability mass function in log space.
std::pair<std::int64_t, std::int64_t> Binomial99(std::int64_t n, double p) {
  double cdf = 0.0;
  std::int64_t lo = -1, hi = n;
  for (std::int64_t k = 0; k <= n; ++k) {
    const double log_pmf = std::lgamma(n + 1.0) - std::lgamma(k + 1.0) - std::lgamma(n - k + 1.0) +
                           k * std::log(p) + (n - k) * std::log1p(-p);
    cdf += std::exp(log_pmf);
    if (lo < 0 && cdf >= 0.005) lo = k;
    if (cdf >= 0.995) {
      hi = k;
      break;
    }
  }
  return {lo, hi};
}

double Phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }
double PhiDensity(double x) { return std::exp(-0.5 * x * x) / std::sqrt(2.0 * kPi); }

struct Moments {
  double mean = 0.0;
  double std = 0.0;
  double min = 0.0;
};
Moments SampleMoments(const std::vector<double>& x) {
  Moments m;
  m.min = x.front();
  for (double v : x) m.mean += v, m.min = std::min(m.min, v);
  m.mean /= static_cast<double>(x.size());
  double ss = 0.0;
  for (double v : x) ss += (v - m.mean) * (v - m.mean);
  m.std = std::sqrt(ss / static_cast<double>(x.size() - 1));
  return m;
}

// Extra delay J of n single-fragment messages, in ms, far enough apart that
// none waits: J = arrival - send - serialization - latency.
std::vector<double> JitterSamples(const LinkConfig& c, int n) {
  Bench b(c, 11);
  const std::uint32_t bytes = 100;
  for (int i = 0; i < n; ++i) b.SendAt(Milliseconds(10.0 * i), bytes);
  b.sim.Run();
  const SimTime fixed = b.link.SerializationNs(bytes + 28) + Milliseconds(c.latency_ms);
  std::vector<double> j;
  for (const Record& r : b.records) {
    REQUIRE(r.arrived);
    j.push_back(static_cast<double>(r.t_arrival_ns - r.t_sent_ns - fixed) * 1e-6);
  }
  return j;
}

}  // namespace

TEST_CASE("Uplink: serialization delay is bytes * 8 / bandwidth exactly", "[channel]") {
  LinkConfig c = QuietLink();
  Bench b(c);
  // 1472 + 28 = 1500 B at 20 Mbps: 12000 bits / 20e6 bit/s = 600 us.
  b.SendAt(0, 1472);
  // 3000 B: fragments of 1472, 1472 and 56 B, i.e. 1500 + 1500 + 84 B on the
  // wire: 24672 bits = 1233.6 us.
  b.SendAt(Seconds(1.0), 3000);
  // Queued behind a 1500 B fragment sent at the same instant: it waits 600 us.
  b.SendAt(Seconds(2.0), 1472);
  b.SendAt(Seconds(2.0), 72);  // 100 B on the wire: 40 us
  b.sim.Run();
  CHECK(b.records[0].t_arrival_ns == 600000);
  CHECK(b.records[1].t_arrival_ns == Seconds(1.0) + 1233600);
  CHECK(b.records[2].t_arrival_ns == Seconds(2.0) + 600000);
  CHECK(b.records[3].t_arrival_ns == Seconds(2.0) + 600000 + 40000);

  c.bandwidth_mbps = 100.0;
  c.latency_ms = 5.0;
  Bench fast(c);
  fast.SendAt(0, 972);  // 1000 B: 8000 bits / 100e6 = 80 us, then 5 ms
  fast.sim.Run();
  CHECK(fast.records[0].t_arrival_ns == 80000 + 5000000);
  CHECK(fast.link.SerializationNs(1000) == 80000);
}

TEST_CASE("Uplink: fragmentation over the MTU", "[channel]") {
  using uavsim::channel::LatentMessageBytes;
  CHECK(LatentMessageBytes(16) == 16 + 64);
  CHECK(Fragment(1, 1500, 28).count == 1);
  CHECK(Fragment(1, 1500, 28).last_wire_bytes == 29);
  CHECK(Fragment(1472, 1500, 28).count == 1);
  CHECK(Fragment(1472, 1500, 28).last_wire_bytes == 1500);
  CHECK(Fragment(1473, 1500, 28).count == 2);
  CHECK(Fragment(1473, 1500, 28).last_wire_bytes == 29);
  CHECK(Fragment(1473, 1500, 28).full_wire_bytes == 1500);
  CHECK(Fragment(4000000000u, 1500, 28).count == 2717392);  // ceil(4e9 / 1472)
  CHECK(Fragment(100, 64, 0).count == 2);
  CHECK(Fragment(100, 64, 0).last_wire_bytes == 36);
}

TEST_CASE("Uplink: Bernoulli loss lies in its binomial 99 % interval", "[channel]") {
  LinkConfig c = QuietLink();
  c.loss.type = LossType::kBernoulli;
  c.loss.p = 0.2;
  Bench b(c);
  const int n = 100000;
  for (int i = 0; i < n; ++i) b.SendAt(Milliseconds(1.0 * i), 80);
  b.sim.Run();
  const auto [lo, hi] = Binomial99(n, 0.2);
  const auto lost = static_cast<std::int64_t>(b.Lost());
  INFO("lost " << lost << " of " << n << ", 99 % interval [" << lo << ", " << hi << "]");
  CHECK(lost >= lo);
  CHECK(lost <= hi);
  for (const Record& r : b.records) {
    CHECK(r.arrived != r.lost);
    if (r.lost) CHECK(r.cause == LossCause::kChannel);
  }
  CHECK(b.link.stats().messages_lost == b.Lost());
  CHECK(b.link.stats().messages_delivered + b.link.stats().messages_lost == n);
}

TEST_CASE("Uplink: a message of n fragments is lost with probability 1 - (1 - p)^n", "[channel]") {
  LinkConfig c = QuietLink();
  c.loss.type = LossType::kBernoulli;
  c.loss.p = 0.05;
  Bench b(c, 3);
  const int n = 20000;
  // 4 * 1472 B: four full fragments, 2.4 ms on the wire; one every 5 ms.
  for (int i = 0; i < n; ++i) b.SendAt(Milliseconds(5.0 * i), 4 * 1472);
  b.sim.Run();
  const double p_message = 1.0 - std::pow(1.0 - 0.05, 4);
  const auto [lo, hi] = Binomial99(n, p_message);
  const auto lost = static_cast<std::int64_t>(b.Lost());
  INFO("lost " << lost << ", 99 % interval [" << lo << ", " << hi << "]");
  CHECK(lost >= lo);
  CHECK(lost <= hi);
  CHECK(b.link.stats().fragments_sent == 4u * n);
}

TEST_CASE("Uplink: Gilbert-Elliott bursts last 1/r and lose p/(p+r) of the packets", "[channel]") {
  LinkConfig c = QuietLink();
  c.loss.type = LossType::kGilbertElliott;
  c.loss.p = 0.05;
  c.loss.r = 0.25;
  c.loss.loss_good = 0.0;
  c.loss.loss_bad = 1.0;
  Bench b(c, 5);
  const int n = 200000;
  for (int i = 0; i < n; ++i) b.SendAt(Milliseconds(0.5 * i), 80);
  b.sim.Run();

  std::vector<int> bursts;
  int run = 0;
  for (const Record& r : b.records) {
    if (r.lost) {
      ++run;
    } else if (run > 0) {
      bursts.push_back(run);
      run = 0;
    }
  }
  const double pi_bad = 0.05 / (0.05 + 0.25);
  const double loss_rate = static_cast<double>(b.Lost()) / n;
  // The chain's loss indicator has lag-one correlation 1 - p - r, so the
  // variance of the mean is pi (1 - pi) (2 - p - r) / (p + r) / n.
  const double lambda = 1.0 - 0.05 - 0.25;
  const double sd_rate = std::sqrt(pi_bad * (1 - pi_bad) * (1 + lambda) / (1 - lambda) / n);
  INFO("loss rate " << loss_rate << ", stationary " << pi_bad << ", sd " << sd_rate);
  CHECK(std::abs(loss_rate - pi_bad) < 5 * sd_rate);

  double mean_burst = 0.0;
  for (int l : bursts) mean_burst += l;
  mean_burst /= static_cast<double>(bursts.size());
  // Bursts are geometric with mean 1/r and variance (1 - r)/r^2.
  const double sd_burst =
      std::sqrt((1 - 0.25) / (0.25 * 0.25) / static_cast<double>(bursts.size()));
  INFO("mean burst " << mean_burst << " over " << bursts.size() << " bursts, sd " << sd_burst);
  CHECK(std::abs(mean_burst - 1.0 / 0.25) < 5 * sd_burst);
  // And P(burst of length 1) = r.
  double ones = 0;
  for (int l : bursts) ones += (l == 1);
  const double sd_ones = std::sqrt(0.25 * 0.75 / static_cast<double>(bursts.size()));
  CHECK(std::abs(ones / static_cast<double>(bursts.size()) - 0.25) < 5 * sd_ones);
}

TEST_CASE("Uplink: outages drop exactly the packets inside them", "[channel]") {
  LinkConfig c = QuietLink();
  c.latency_ms = 2.0;
  // Link down on [200.5, 300) ms, [500.02, 600) ms; node "lidar1" down on
  // [400, 450) ms.
  c.outages = {OutageConfig{0.2005, 0.3, {}}, OutageConfig{0.50002, 0.6, {}},
               OutageConfig{0.4, 0.45, {"lidar1"}}};
  Bench b(c, 1, 0.0, {"cam1", "lidar1"});
  // Each ms: cam1 sends at k ms, lidar1 at k + 0.5 ms; 100 B on the wire
  // (40 us of serialization).
  for (int k = 0; k < 1000; ++k) {
    b.SendAt(Milliseconds(k), 72, 0);
    b.SendAt(Milliseconds(k + 0.5), 72, 1);
  }
  b.sim.Run();
  const double ser_ms = 0.04;
  for (const Record& r : b.records) {
    const double t_ms = static_cast<double>(r.t_sent_ns) * 1e-6;
    const bool lidar = r.node == 1;
    // A fragment is lost if [t, t + ser) overlaps a link outage.
    const bool link_down =
        (t_ms < 300.0 && t_ms + ser_ms > 200.5) || (t_ms < 600.0 && t_ms + ser_ms > 500.02);
    const bool node_down = lidar && t_ms >= 400.0 && t_ms < 450.0;
    INFO("message sent at " << t_ms << " ms");
    CHECK(r.lost == (link_down || node_down));
    CHECK(r.arrived == !r.lost);
    if (node_down) CHECK(r.cause == LossCause::kNodeDown);
    if (link_down && !node_down) CHECK(r.cause == LossCause::kLinkDown);
  }
  // Spelled out: the first link outage takes cam1's 201..299 ms and lidar1's
  // 200.5..299.5 ms messages, the second cam1's 500..599 ms and lidar1's
  // 500.5..599.5 ms ones; the node outage lidar1's 400..449.5 ms ones.
  CHECK(b.Lost() == (99 + 100) + (100 + 100) + 50);
  CHECK(b.link.stats().messages_lost_by_cause[static_cast<int>(LossCause::kNodeDown)] == 50);
  // cam1 at 500 ms: on the wire [500, 500.04) ms when the link goes down at 500.02.
  CHECK(b.records[2 * 500].lost);
  CHECK(b.records[2 * 600].arrived);  // starts at 600 ms exactly, when the link is back
}

TEST_CASE("Uplink: drop-tail drops exactly what exceeds the buffer", "[channel]") {
  LinkConfig c = QuietLink();
  c.buffer_packets = 10;
  const SimTime s = 600000;  // one 1500 B fragment at 20 Mbps

  SECTION("a burst of single-fragment messages") {
    Bench b(c);
    // One goes on the wire, ten wait, the other 14 are dropped.
    for (int i = 0; i < 25; ++i) b.SendAt(0, 1472);
    // At 3.5 s-units the 4th fragment is on the wire and 7 wait: 3 places left.
    for (int i = 0; i < 5; ++i) b.SendAt(7 * s / 2, 1472);
    b.sim.Run();
    for (int i = 0; i < 25; ++i) {
      INFO("message " << i);
      CHECK(b.records[i].lost == (i >= 11));
      if (i >= 11) CHECK(b.records[i].cause == LossCause::kBufferFull);
    }
    for (int i = 25; i < 30; ++i) CHECK(b.records[i].lost == (i >= 28));
    CHECK(b.Lost() == 14 + 2);
    // FIFO: the k-th admitted fragment finishes at (k + 1) s.
    CHECK(b.records[10].t_arrival_ns == 11 * s);
    CHECK(b.records[27].t_arrival_ns == 14 * s);
  }
  SECTION("fragments count against the buffer, and the wire drains it") {
    Bench b(c);
    // 3 messages of 5 fragments: 1 on the wire + 10 waiting = 11 fragments fit,
    // so the third message loses 4 of its 5 fragments.
    for (int i = 0; i < 3; ++i) b.SendAt(0, 5 * 1472);
    b.SendAt(11 * s, 5 * 1472);  // the buffer has drained by then
    b.sim.Run();
    CHECK(b.records[0].arrived);
    CHECK(b.records[1].arrived);
    CHECK(b.records[2].lost);
    CHECK(b.records[2].cause == LossCause::kBufferFull);
    CHECK(b.link.stats().fragments_lost_by_cause[static_cast<int>(LossCause::kBufferFull)] == 4);
    CHECK(b.records[3].arrived);
    CHECK(b.records[3].t_arrival_ns == 11 * s + 5 * s);
  }
}

TEST_CASE("Uplink: jitter is never negative and has the configured spread", "[channel]") {
  LinkConfig c = QuietLink();
  const int n = 40000;

  SECTION("normal, truncation negligible: mean 0, std as configured") {
    c.latency_ms = 5.0;
    c.jitter.type = JitterType::kNormal;
    c.jitter.std_ms = 1.0;  // truncation at -5 sigma
    const Moments m = SampleMoments(JitterSamples(c, n));
    CHECK(m.min >= -5.0);
    CHECK(std::abs(m.mean) < 5 * 1.0 / std::sqrt(n));
    CHECK(m.std == Approx(1.0).epsilon(0.03));
  }
  SECTION("normal truncated at zero delay: the half-normal law") {
    c.latency_ms = 0.0;
    c.jitter.type = JitterType::kNormal;
    c.jitter.std_ms = 2.0;
    const Moments m = SampleMoments(JitterSamples(c, n));
    CHECK(m.min >= 0.0);
    CHECK(m.mean == Approx(2.0 * std::sqrt(2.0 / kPi)).epsilon(0.02));
    CHECK(m.std == Approx(2.0 * std::sqrt(1.0 - 2.0 / kPi)).epsilon(0.03));
  }
  SECTION("normal truncated at latency + J = 0: the truncated-normal law") {
    c.latency_ms = 1.0;
    c.jitter.type = JitterType::kNormal;
    c.jitter.std_ms = 2.0;
    // J ~ N(0, s^2) given J >= a s, a = -latency / s: with h = phi(a) / (1 - Phi(a)),
    // E J = s h and Var J = s^2 (1 + a h - h^2).
    const double s = 2.0, a = -0.5;
    const double h = PhiDensity(a) / (1.0 - Phi(a));
    const Moments m = SampleMoments(JitterSamples(c, n));
    CHECK(m.min >= -1.0);
    CHECK(m.mean == Approx(s * h).epsilon(0.03));
    CHECK(m.std == Approx(s * std::sqrt(1.0 + a * h - h * h)).epsilon(0.03));
  }
  SECTION("uniform on [0, max]") {
    c.latency_ms = 3.0;
    c.jitter.type = JitterType::kUniform;
    c.jitter.max_ms = 4.0;
    const Moments m = SampleMoments(JitterSamples(c, n));
    CHECK(m.min >= 0.0);
    CHECK(m.mean == Approx(2.0).epsilon(0.02));
    CHECK(m.std == Approx(4.0 / std::sqrt(12.0)).epsilon(0.02));
  }
  SECTION("pareto (Lomax): mean scale/(shape-1), variance scale^2 shape/((shape-1)^2 (shape-2))") {
    c.latency_ms = 3.0;
    c.jitter.type = JitterType::kPareto;
    c.jitter.scale_ms = 1.0;
    c.jitter.shape = 6.0;
    const Moments m = SampleMoments(JitterSamples(c, 100000));
    CHECK(m.min >= 0.0);
    CHECK(m.mean == Approx(1.0 / 5.0).epsilon(0.03));
    CHECK(m.std == Approx(std::sqrt(6.0 / (25.0 * 4.0))).epsilon(0.06));
  }
}

TEST_CASE("Uplink: jitter reorders messages, a seed fixes every fate and delay", "[channel]") {
  LinkConfig c = QuietLink();
  c.latency_ms = 10.0;
  c.jitter.type = JitterType::kNormal;
  c.jitter.std_ms = 5.0;
  c.loss.type = LossType::kGilbertElliott;
  c.loss.p = 0.1;
  c.loss.r = 0.3;
  struct Outcome {
    std::vector<Record> records;
    std::vector<std::uint64_t> arrival_order;
  };
  auto run = [](const LinkConfig& cfg, std::uint64_t seed) {
    Bench b(cfg, seed);
    for (int i = 0; i < 2000; ++i) b.SendAt(Milliseconds(1.0 * i), 80);
    b.sim.Run();
    return Outcome{b.records, b.arrival_order};
  };
  const Outcome a = run(c, 42);
  const Outcome again = run(c, 42);
  bool reordered = false;
  for (std::size_t i = 1; i < a.arrival_order.size(); ++i)
    reordered |= a.arrival_order[i] < a.arrival_order[i - 1];
  CHECK(reordered);
  CHECK(a.arrival_order == again.arrival_order);
  bool same = true;
  for (std::size_t i = 0; i < a.records.size(); ++i)
    same &= a.records[i].lost == again.records[i].lost &&
            a.records[i].t_arrival_ns == again.records[i].t_arrival_ns;
  CHECK(same);

  // The loss stream is apart from the jitter stream: other jitter, same losses.
  LinkConfig other = c;
  other.jitter.std_ms = 1.0;
  const Outcome b = run(other, 42);
  bool same_losses = true;
  for (std::size_t i = 0; i < a.records.size(); ++i)
    same_losses &= a.records[i].lost == b.records[i].lost;
  CHECK(same_losses);
  // Another seed, another pattern.
  const Outcome d = run(c, 43);
  bool differs = false;
  for (std::size_t i = 0; i < a.records.size(); ++i)
    differs |= a.records[i].lost != d.records[i].lost;
  CHECK(differs);
}

TEST_CASE("Uplink: bit error rates of the modulations", "[channel]") {
  auto db = [](double x) { return 10.0 * std::log10(x); };
  // Textbook anchors: BER 1e-5 at Eb/N0 = 9.6 dB for BPSK and QPSK (Es = 2 Eb)
  // and about 13.4 dB for Gray-mapped 16-QAM (Es = 4 Eb).
  CHECK(BitErrorRate(Modulation::kBpsk, 9.59) == Approx(1e-5).epsilon(0.05));
  CHECK(BitErrorRate(Modulation::kQpsk, 9.59 + db(2)) == Approx(1e-5).epsilon(0.05));
  CHECK(BitErrorRate(Modulation::kQam16, 13.4 + db(4)) == Approx(1e-5).epsilon(0.2));
  // The closed forms: Q(sqrt(2 g)) for BPSK; (4/k)(1 - 2^(-k/2)) Q(sqrt(3 g/(M-1))).
  auto q = [](double x) { return 0.5 * std::erfc(x / std::sqrt(2.0)); };
  const double g = std::pow(10.0, 1.8);  // 18 dB
  CHECK(BitErrorRate(Modulation::kBpsk, 18.0) == Approx(q(std::sqrt(2 * g))));
  CHECK(BitErrorRate(Modulation::kQpsk, 18.0) == Approx(q(std::sqrt(g))));
  CHECK(BitErrorRate(Modulation::kQam64, 18.0) ==
        Approx(4.0 / 6.0 * (1 - 1 / 8.0) * q(std::sqrt(3 * g / 63))));
  CHECK(BitErrorRate(Modulation::kQam256, 18.0) ==
        Approx(4.0 / 8.0 * (1 - 1 / 16.0) * q(std::sqrt(3 * g / 255))));
  CHECK(BitErrorRate(Modulation::kQam256, -40.0) <= 0.5);
  CHECK(BitErrorRate(Modulation::kBpsk, -40.0) == Approx(0.5).margin(0.01));
  CHECK(BitErrorRate(Modulation::kQam16, 60.0) == 0.0);
}

TEST_CASE("Uplink: rain on a 28 GHz link lowers the SNR and loses packets at the PER",
          "[channel]") {
  LinkConfig c = QuietLink();
  c.snr_db = 25.0;
  c.modulation = Modulation::kQam16;
  c.carrier_ghz = 28.0;
  c.path_length_m = 1000.0;
  c.polarization = uavsim::core::Polarization::kHorizontal;
  Bench b(c, 9, 25.0);
  // P.838-3 Table 5 at 28 GHz, horizontal: k = 0.2051, alpha = 0.9679; 1 km.
  const double a_rain = 0.2051 * std::pow(25.0, 0.9679);
  CHECK(b.link.rain_attenuation_db() == Approx(a_rain).epsilon(1e-3));
  CHECK(b.link.snr_db() == Approx(25.0 - a_rain).epsilon(1e-3));
  const double gamma = std::pow(10.0, (25.0 - a_rain) / 10.0);
  const double ber = 0.75 * 0.5 * std::erfc(std::sqrt(3.0 * gamma / 15.0) / std::sqrt(2.0));
  CHECK(b.link.bit_error_rate() == Approx(ber).epsilon(0.01));
  const double per = 1.0 - std::pow(1.0 - ber, 8.0 * 1500);
  CHECK(b.link.FragmentErrorRate(1500) == Approx(per).epsilon(0.01));

  const int n = 20000;
  for (int i = 0; i < n; ++i) b.SendAt(Milliseconds(1.0 * i), 1472);
  b.sim.Run();
  const auto [lo, hi] = Binomial99(n, b.link.FragmentErrorRate(1500));
  const auto lost = static_cast<std::int64_t>(b.Lost());
  INFO("PER " << per << ": lost " << lost << ", 99 % interval [" << lo << ", " << hi << "]");
  CHECK(lost >= lo);
  CHECK(lost <= hi);
  for (const Record& r : b.records)
    if (r.lost) CHECK(r.cause == LossCause::kBitErrors);

  // Dry, the same link loses nothing measurable; heavier rain loses more.
  b.link.SetWeather(WeatherConfig{0.0, {}, 1.0});
  CHECK(b.link.rain_attenuation_db() == 0.0);
  CHECK(b.link.FragmentErrorRate(1500) < 1e-9);
  b.link.SetWeather(WeatherConfig{50.0, {}, 1.0});
  CHECK(b.link.FragmentErrorRate(1500) > 0.5);
  // Without a carrier, rain does not touch the link.
  c.carrier_ghz.reset();
  Bench dry(c, 9, 100.0);
  CHECK(dry.link.rain_attenuation_db() == 0.0);
  CHECK(dry.link.snr_db() == 25.0);
}

TEST_CASE("Uplink: messages still on the link at the end are in flight", "[channel]") {
  LinkConfig c = QuietLink();
  c.latency_ms = 50.0;
  Bench b(c);
  b.SendAt(0, 80);
  b.SendAt(Milliseconds(100), 80);
  b.sim.RunUntil(Milliseconds(120));
  CHECK(b.records[0].arrived);
  CHECK_FALSE(b.records[1].arrived);
  CHECK(b.link.stats().messages_in_flight() == 1);
}

TEST_CASE("Uplink: bad configurations and messages are refused", "[channel]") {
  Simulator sim;
  const WeatherConfig dry;
  LinkConfig c = QuietLink();
  c.buffer_packets = 0;
  try {
    Uplink link(sim, c, dry, RngStream(1, "l"));
    FAIL("no throw");
  } catch (const uavsim::core::ConfigError& e) {
    CHECK(std::string(e.what()) ==
          "uplink config: /buffer_packets: expected an integer in [1, 10000000], got 0");
  }
  c = QuietLink();
  c.outages = {OutageConfig{1.0, 2.0, {"ghost"}}};
  CHECK_THROWS_AS(Uplink(sim, c, dry, RngStream(1, "l"), {"cam1"}), std::invalid_argument);
  Uplink link(sim, QuietLink(), dry, RngStream(1, "l"), {"cam1"});
  Message empty;
  CHECK_THROWS_AS(link.Send(empty), std::invalid_argument);
  Message stranger;
  stranger.payload_bytes = 10;
  stranger.node = 1;
  CHECK_THROWS_AS(link.Send(stranger), std::invalid_argument);
  CHECK_THROWS_AS(link.SetWeather(WeatherConfig{-1.0, {}, 1.0}), std::invalid_argument);
}
