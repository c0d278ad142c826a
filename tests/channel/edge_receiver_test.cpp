#include "channel/edge_receiver.h"

#include <catch2/catch.hpp>
#include <stdexcept>
#include <vector>

#include "channel/packet.h"
#include "core/time.h"

using uavsim::channel::EdgeReceiver;
using uavsim::channel::Message;
using uavsim::channel::Modality;
using uavsim::channel::Percentile;
using uavsim::core::Json;
using uavsim::core::Milliseconds;
using uavsim::core::Seconds;
using uavsim::core::SimTime;

namespace {

Message Captured(Modality m, SimTime t_capture_ns) {
  Message msg;
  msg.modality = m;
  msg.t_capture_ns = t_capture_ns;
  msg.payload_bytes = 80;
  return msg;
}

}  // namespace

TEST_CASE("EdgeReceiver: late is after the deadline of the capture's window", "[channel]") {
  const EdgeReceiver rx(0.2, 0.05);
  // Window 0 is [0, 0.2) s, deadline 0.2 + 0.05 s.
  CHECK(rx.DeadlineNs(0) == Milliseconds(250));
  CHECK(rx.DeadlineNs(Seconds(0.2) - 1) == Milliseconds(250));
  // A capture exactly on a boundary opens the next window.
  CHECK(rx.DeadlineNs(Seconds(0.2)) == Milliseconds(450));
  CHECK(rx.DeadlineNs(Seconds(59.9)) == Seconds(60.05));
  // Arriving exactly at the deadline is on time; one nanosecond later is late.
  CHECK_FALSE(rx.IsLate(Seconds(0.1), Milliseconds(250)));
  CHECK(rx.IsLate(Seconds(0.1), Milliseconds(250) + 1));
  CHECK_FALSE(rx.IsLate(Seconds(0.2), Milliseconds(449)));
  CHECK(rx.IsLate(Seconds(0.2) - 1, Milliseconds(251)));

  const EdgeReceiver strict(0.2, 0.0);
  CHECK(strict.IsLate(Seconds(0.199), Seconds(0.2) + 1));
  CHECK_FALSE(strict.IsLate(Seconds(0.199), Seconds(0.2)));
}

TEST_CASE("EdgeReceiver: counts per modality add up", "[channel]") {
  EdgeReceiver rx(0.2, 0.0);
  const Message cam0 = Captured(Modality::kCamera, Milliseconds(10));
  const Message cam1 = Captured(Modality::kCamera, Milliseconds(190));
  const Message cam2 = Captured(Modality::kCamera, Milliseconds(195));
  const Message cam3 = Captured(Modality::kCamera, Milliseconds(199));
  const Message lidar = Captured(Modality::kLidar, Milliseconds(100));
  for (const Message* m : {&cam0, &cam1, &cam2, &cam3, &lidar}) rx.OnSent(*m);
  CHECK(rx.OnArrival(cam0, Milliseconds(30)));
  CHECK_FALSE(rx.OnArrival(cam1, Milliseconds(205)));
  rx.OnLost(cam2);
  CHECK(rx.OnArrival(lidar, Milliseconds(200)));
  const auto& c = rx.Counts(Modality::kCamera);
  CHECK(c.sent == 4);
  CHECK(c.delivered == 1);
  CHECK(c.late == 1);
  CHECK(c.lost == 1);
  CHECK(c.in_flight() == 1);  // cam3
  CHECK(rx.Counts(Modality::kLidar).delivered == 1);
  CHECK(rx.Counts(Modality::kRadar).sent == 0);
  // Latency counts every arrival, late ones too: 20 ms and 15 ms.
  const auto l = rx.Latency(Modality::kCamera);
  CHECK(l.count == 2);
  CHECK(l.mean_s == Approx(0.0175));
  CHECK(l.max_s == Approx(0.020));
  // Arrivals and losses of messages never reported sent are bugs of the caller.
  CHECK_THROWS_AS(rx.OnArrival(Captured(Modality::kRadar, 0), 5), std::logic_error);
  CHECK_THROWS_AS(rx.OnLost(Captured(Modality::kRadar, 0)), std::logic_error);
}

TEST_CASE("EdgeReceiver: percentiles of a known list", "[channel]") {
  // numpy.percentile([1..10], q) with the default linear interpolation.
  const std::vector<double> x{7, 3, 10, 1, 5, 2, 9, 4, 8, 6};
  CHECK(Percentile(x, 0.50) == Approx(5.5));
  CHECK(Percentile(x, 0.95) == Approx(9.55));
  CHECK(Percentile(x, 0.99) == Approx(9.91));
  CHECK(Percentile(x, 0.0) == 1.0);
  CHECK(Percentile(x, 1.0) == 10.0);
  CHECK(Percentile({4.0}, 0.99) == 4.0);
  CHECK(Percentile({1.0, 2.0, 3.0, 4.0}, 0.5) == Approx(2.5));
  CHECK_THROWS_AS(Percentile({}, 0.5), std::invalid_argument);
  CHECK_THROWS_AS(Percentile(x, 1.5), std::invalid_argument);

  // The receiver's summary: latencies 1..100 ms.
  EdgeReceiver rx(0.2, 10.0);
  for (int i = 1; i <= 100; ++i) {
    const Message m = Captured(Modality::kRadar, Seconds(1.0));
    rx.OnSent(m);
    rx.OnArrival(m, Seconds(1.0) + Milliseconds(i));
  }
  const auto l = rx.Latency(Modality::kRadar);
  CHECK(l.count == 100);
  CHECK(l.mean_s == Approx(0.0505));
  CHECK(l.p50_s == Approx(0.0505));
  CHECK(l.p95_s == Approx(0.09505));
  CHECK(l.p99_s == Approx(0.09901));
  CHECK(l.max_s == Approx(0.100));
}

TEST_CASE("EdgeReceiver: metrics merge into the modalities object", "[channel]") {
  EdgeReceiver rx(0.2, 0.0);
  const Message m = Captured(Modality::kLidar, 0);
  rx.OnSent(m);
  rx.OnSent(m);
  rx.OnArrival(m, Milliseconds(12));
  Json modalities = {{"lidar", {{"frames", 2}}}};
  rx.WriteMetrics(modalities);
  const Json& lidar = modalities["lidar"];
  CHECK(lidar["frames"] == 2);
  CHECK(lidar["packets_sent"] == 2);
  CHECK(lidar["packets_delivered"] == 1);
  CHECK(lidar["packets_late"] == 0);
  CHECK(lidar["packets_lost"] == 0);
  CHECK(lidar["packets_in_flight"] == 1);
  CHECK(lidar["latency_s"]["count"] == 1);
  CHECK(lidar["latency_s"]["p99"].get<double>() == Approx(0.012));
  CHECK(modalities["camera"]["packets_sent"] == 0);
  CHECK(modalities["camera"]["latency_s"]["mean"].is_null());
  CHECK(modalities.contains("radar"));
}

TEST_CASE("EdgeReceiver: bad windows throw", "[channel]") {
  CHECK_THROWS_AS(EdgeReceiver(0.0, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(EdgeReceiver(0.2, -0.1), std::invalid_argument);
  CHECK_THROWS_AS(EdgeReceiver(std::nan(""), 0.0), std::invalid_argument);
}
