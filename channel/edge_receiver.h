// The edge server's reception accounting, per modality (camera, LiDAR, radar).
//
// Windows: the alignment window of a capture at t_c is
//   k = floor(t_c / window_s),   covering [k w, (k + 1) w),
// computed on integer nanoseconds (a capture exactly at k w opens window k).
// Its deadline is (k + 1) w + late_allowance_s. A message arriving at
// t_a <= deadline is delivered (on time); t_a > deadline is late, and the
// pipeline treats it as missing.
//
// Counters (messages, one per frame; "packets" in metrics.json):
//   sent       every message the engine offers to a link (OnSent)
//   delivered  arrived on time           late  arrived after its deadline
//   lost       never arrives (OnLost)    in_flight = sent - delivered - late - lost
// so sent = delivered + late + lost + in_flight (in flight: still on the link
// when the run ends).
//
// Latency is t_a - t_c over every arrival, on time or late, in seconds:
// mean, and the percentiles p50, p95, p99 by linear interpolation between
// order statistics (Percentile below).
//
// The log keeps every message's fate in the order messages were sent (the
// run's packets.csv).
//
// Determinism: pure bookkeeping, no randomness. Not thread-safe.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "channel/packet.h"
#include "core/json_io.h"
#include "core/time.h"

namespace uavsim::channel {

struct ReceptionCounts {
  std::uint64_t sent = 0;
  std::uint64_t delivered = 0;
  std::uint64_t late = 0;
  std::uint64_t lost = 0;
  std::uint64_t in_flight() const { return sent - delivered - late - lost; }
};

struct LatencySummary {
  std::uint64_t count = 0;  // arrivals; the statistics below are 0 when count is 0
  double mean_s = 0.0;
  double p50_s = 0.0;
  double p95_s = 0.0;
  double p99_s = 0.0;
  double max_s = 0.0;
};

// What became of one message.
enum class Fate { kInFlight, kDelivered, kLate, kLost };
const char* FateName(Fate f);  // "in_flight", "delivered", "late", "lost"

struct MessageRecord {
  std::uint32_t node = 0;  // the sender's index in the scenario's node list
  Modality modality = Modality::kCamera;
  std::uint64_t sequence = 0;
  core::SimTime t_capture_ns = 0;
  std::uint32_t payload_bytes = 0;
  Fate fate = Fate::kInFlight;
  core::SimTime t_arrival_ns = -1;  // delivered or late; -1 otherwise
};

// The q-quantile (q in [0, 1]) of `values` by linear interpolation between
// order statistics x_(0) <= ... <= x_(n-1) (Hyndman & Fan type 7, numpy's
// default): h = (n - 1) q, x_(floor h) + (h - floor h) (x_(floor h + 1) -
// x_(floor h)). `values` need not be sorted. Throws std::invalid_argument if
// `values` is empty or q is outside [0, 1].
double Percentile(std::vector<double> values, double q);

class EdgeReceiver {
 public:
  // window_s: the pipeline's alignment window (paper: 0.2 s), > 0;
  // late_allowance_s >= 0. Throws std::invalid_argument otherwise.
  EdgeReceiver(double window_s, double late_allowance_s);

  // Feed: the engine calls OnSent for each message it hands to a link, and
  // wires the link's callbacks to OnArrival and OnLost. OnArrival returns true
  // if the message is on time (pass it to the pipeline), false if late. A
  // message that was not reported sent throws std::logic_error (its modality
  // would account more arrivals and losses than sends).
  void OnSent(const Message& message);
  bool OnArrival(const Message& message, core::SimTime t_arrival_ns);
  void OnLost(const Message& message);

  // The deadline of the window that t_capture_ns (>= 0) falls in.
  core::SimTime DeadlineNs(core::SimTime t_capture_ns) const;
  bool IsLate(core::SimTime t_capture_ns, core::SimTime t_arrival_ns) const {
    return t_arrival_ns > DeadlineNs(t_capture_ns);
  }

  const ReceptionCounts& Counts(Modality m) const { return counts_[Index(m)]; }
  // Every message reported sent, in that order, with its fate so far.
  const std::vector<MessageRecord>& log() const { return log_; }
  LatencySummary Latency(Modality m) const;

  // Merges into `modalities` (an object keyed "camera", "lidar", "radar", as
  // metrics.json's "modalities"), for every modality, the keys
  //   packets_sent, packets_delivered, packets_late, packets_lost,
  //   packets_in_flight, latency_s: {count, mean, p50, p95, p99, max}
  // (latency statistics are null when nothing arrived). Keys already there
  // (e.g. "frames") are kept.
  void WriteMetrics(core::Json& modalities) const;

 private:
  static std::size_t Index(Modality m) { return static_cast<std::size_t>(m); }

  core::SimTime window_ns_;
  core::SimTime allowance_ns_;
  std::array<ReceptionCounts, kModalityCount> counts_{};
  std::array<std::vector<core::SimTime>, kModalityCount> latencies_ns_;
  std::vector<MessageRecord> log_;
  // (node, sequence) -> index in log_ of the messages still in flight.
  std::map<std::pair<std::uint32_t, std::uint64_t>, std::size_t> in_flight_;
  // The log entry of a message in flight (removed from in_flight_), or null.
  MessageRecord* Resolve(const Message& message);
};

}  // namespace uavsim::channel
