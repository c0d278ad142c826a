// One uplink (an entry of the scenario's "links"), shared by the sensing nodes
// that name it, driven by a core::Simulator and its own random stream.
//
// A message sent at t = sim.Now() is cut into n fragments (packet.h) that
// enter one FIFO transmitter in order. For fragment i with w_i wire bytes:
//
//   serialization   s_i = w_i * 8 / bandwidth, rounded to the nanosecond:
//                   round(8000 * w_i / bandwidth_mbps) ns
//   start           t_start_i = max(t, end of the previous fragment on the wire)
//   arrival         a_i = t_start_i + s_i + latency + J_i, J_i the jitter
//                   (JitterConfig; latency + J_i >= 0, J_i capped at 1e9 s)
//
// and the message arrives at max_i a_i, if no fragment is lost. Jitter is drawn
// per fragment, so fragments and messages may be reordered.
//
// A fragment is lost, in this order of causes (LossCause):
//  1. kNodeDown   the sender is down at t (OutageConfig with nodes): the whole
//                 message is lost at the node and never reaches the buffer.
//  2. kBufferFull drop-tail: it would wait (t_start_i > t) while buffer_packets
//                 fragments are already waiting. The fragment on the wire is
//                 not counted; a dropped fragment takes no wire time.
//  3. kLinkDown   its serialization interval [t_start_i, t_start_i + s_i)
//                 overlaps a link outage [from_s, to_s) (it still takes wire
//                 time: the transmitter drains into a dead link).
//  4. kChannel    the loss model, drawn for every fragment on the air while
//                 the link is up: bernoulli, lost with probability p;
//                 gilbert_elliott, a two-state Markov chain stepped once per
//                 fragment (good -> bad with p, bad -> good with r) and then
//                 lost with loss_good or loss_bad in the new state. The chain
//                 starts in its stationary law, P(bad) = p / (p + r), so its
//                 loss rate is stationary from the first fragment:
//                 (p loss_bad + r loss_good) / (p + r); bad bursts last 1/r
//                 fragments on average.
//  5. kBitErrors  the radio's packet error rate at the current SNR:
//                   A_rain = gamma_R(carrier_ghz, rain_mm_h) * path_length_m / 1000 [dB]
//                            (ITU-R P.838-3, core/rain_attenuation.h; uniform rain
//                            over the path; 0 without carrier_ghz)
//                   SNR    = snr_db + coding_gain_db - A_rain        [dB, Es/N0]
//                   BER    = BitErrorRate(modulation, SNR)
//                   PER(w) = 1 - (1 - BER)^(8 w)
//                 (independent bit errors; any bit error loses the fragment).
// A message is lost if any fragment is; its cause is the first lost
// fragment's. Losses are decided when the message is sent; the loss callback
// runs inside Send.
//
// Determinism: the loss chain, the bit errors and the jitter each draw from a
// child stream of the RngStream given (Derive("loss"), "bit_errors",
// "jitter"), so one seed fixes every fate and delay, and changing the jitter
// leaves the loss pattern unchanged. Draws are skipped only where they cannot
// matter (a fragment of a message already lost gets no jitter or bit-error
// draw; a probability of exactly 0 or 1 draws nothing).
//
// Cost: Send is O(n) in the message's fragments, with one simulator event per
// delivered message and no heap allocation once the in-flight pool and the
// buffer have grown to their working size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "channel/link_config.h"
#include "channel/packet.h"
#include "core/rng.h"
#include "core/simulator.h"
#include "core/time.h"
#include "core/weather.h"

namespace uavsim::channel {

enum class LossCause : std::uint8_t { kNodeDown, kBufferFull, kLinkDown, kChannel, kBitErrors };
constexpr int kLossCauseCount = 5;
// "node_down", "buffer_full", "link_down", "channel", "bit_errors".
const char* LossCauseName(LossCause cause);

// Bit error rate of uncoded Gray-mapped modulation on an AWGN channel at
// symbol SNR Es/N0 = snr_db, with Q(x) = erfc(x / sqrt 2) / 2 and gamma the
// linear SNR:
//   bpsk               Q(sqrt(2 gamma))
//   M-QAM, M = 4 (qpsk), 16, 64, 256
//                      (4 / log2 M) (1 - 1/sqrt M) Q(sqrt(3 gamma / (M - 1)))
// capped at 1/2. The QAM expression is the nearest-neighbour approximation of
// the square-QAM symbol error rate divided by log2 M (Gray mapping), exact for
// qpsk (Proakis & Salehi, Digital Communications, 5th ed., Sec. 4.3; Goldsmith,
// Wireless Communications, Sec. 6.1). Pure.
double BitErrorRate(Modulation modulation, double snr_db);

// Counters of one link since construction. Messages: every Send is sent and
// ends up delivered, lost or in flight. Fragments: offered to the buffer.
struct UplinkStats {
  std::uint64_t messages_sent = 0;
  std::uint64_t messages_delivered = 0;  // arrival callbacks run
  std::uint64_t messages_lost = 0;
  std::uint64_t messages_lost_by_cause[kLossCauseCount] = {};
  std::uint64_t fragments_sent = 0;
  std::uint64_t fragments_lost_by_cause[kLossCauseCount] = {};  // kNodeDown counts none

  std::uint64_t messages_in_flight() const {
    return messages_sent - messages_delivered - messages_lost;
  }
};

class Uplink {
 public:
  using ArrivalCallback = std::function<void(const Message& message, core::SimTime t_arrival_ns)>;
  using LossCallback = std::function<void(const Message& message, LossCause cause)>;

  // A link with `config` under `weather`, drawing from `rng` (by convention
  // core::RngStream(seed, "link/" + name)). `node_ids` lists the scenario's
  // node ids by node index (Message::node); it resolves the node outages and
  // may be empty if there are none. Throws core::ConfigError (file
  // "uplink config") if `config` breaks a rule of its Visit, and
  // std::invalid_argument if an outage names a node not in `node_ids`.
  // `sim` must outlive the Uplink.
  Uplink(core::Simulator& sim, const LinkConfig& config, const core::WeatherConfig& weather,
         core::RngStream rng, std::vector<std::string> node_ids = {});
  // Cancels the arrivals still pending: their callbacks never run.
  virtual ~Uplink();
  Uplink(const Uplink&) = delete;
  Uplink& operator=(const Uplink&) = delete;

  // Called at the arrival time, from inside a simulator event.
  void SetArrivalCallback(ArrivalCallback callback) { on_arrival_ = std::move(callback); }
  // Called from inside Send for a message that will not arrive.
  void SetLossCallback(LossCallback callback) { on_loss_ = std::move(callback); }

  // Sends `message` at sim.Now() (see the model above). Throws
  // std::invalid_argument if payload_bytes is 0, or if node_ids was given and
  // message.node is not an index into it.
  void Send(Message message);

  // Rain affects the fragments sent from now on. Throws std::invalid_argument
  // for a negative or non-finite rain rate.
  void SetWeather(const core::WeatherConfig& weather);

  // The model's current quantities (see above).
  double rain_attenuation_db() const { return rain_attenuation_db_; }
  double snr_db() const { return snr_db_; }  // SNR after rain and coding gain
  double bit_error_rate() const { return bit_error_rate_; }
  double FragmentErrorRate(std::uint32_t wire_bytes) const;
  core::SimTime SerializationNs(std::uint32_t wire_bytes) const;

  const LinkConfig& config() const { return config_; }
  const UplinkStats& stats() const { return stats_; }

 private:
  struct Interval {
    core::SimTime from_ns;
    core::SimTime to_ns;
  };
  struct InFlight {
    Message message;
    core::EventId arrival;
  };
  // FIFO of the start times of the fragments waiting in the buffer; grows by
  // doubling and never shrinks, so steady state allocates nothing.
  class StartTimes {
   public:
    bool empty() const { return size_ == 0; }
    std::size_t size() const { return size_; }
    core::SimTime front() const { return ring_[head_]; }
    void pop_front();
    void push_back(core::SimTime t);

   private:
    std::vector<core::SimTime> ring_;
    std::size_t head_ = 0;
    std::size_t size_ = 0;
  };

  // The model behind Send, which has counted the message and checked the
  // sender: buffer, wire, loss, bit errors, jitter, scheduling.
  virtual void DoSend(Message&& message);

  bool LinkDown(core::SimTime start_ns, core::SimTime end_ns);
  bool ChannelLoses();
  bool BitErrorsLose(std::uint32_t wire_bytes);
  core::SimTime DrawJitterNs();
  void Lose(const Message& message, LossCause cause);
  void Deliver(std::uint32_t slot);

  core::Simulator& sim_;
  LinkConfig config_;
  core::RngStream loss_rng_;
  core::RngStream bit_error_rng_;
  core::RngStream jitter_rng_;
  std::vector<std::string> node_ids_;
  ArrivalCallback on_arrival_;
  LossCallback on_loss_;

  // Derived once from config_.
  core::SimTime latency_ns_ = 0;
  Fragmentation full_;  // of an MTU-sized chunk, for its wire bytes
  core::SimTime full_serialization_ns_ = 0;
  std::vector<Interval> link_outages_;               // sorted, merged
  std::vector<std::vector<Interval>> node_outages_;  // by node index
  // From the weather.
  double rain_attenuation_db_ = 0.0;
  double snr_db_ = 0.0;
  double bit_error_rate_ = 0.0;
  double log_bit_success_ = 0.0;  // log(1 - BER)
  double full_fragment_error_rate_ = 0.0;

  // State.
  core::SimTime wire_free_ns_ = 0;  // when the last admitted fragment leaves the wire
  StartTimes waiting_;
  std::size_t next_link_outage_ = 0;  // first outage that may still overlap the wire
  bool channel_bad_ = false;          // gilbert_elliott state
  std::vector<InFlight> in_flight_;
  std::vector<std::uint32_t> free_slots_;
  UplinkStats stats_;
};

}  // namespace uavsim::channel
