#include "core/simulator.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/rng.h"
#include "core/time.h"

namespace {

using uavsim::core::EventId;
using uavsim::core::RngStream;
using uavsim::core::SimTime;
using uavsim::core::Simulator;

}  // namespace

TEST_CASE("Simulator: events run in time order", "[core]") {
  Simulator sim;
  std::vector<int> order;
  for (int t : {50, 10, 40, 20, 30}) sim.ScheduleAt(t, [&order, t] { order.push_back(t); });
  CHECK(sim.pending() == 5);
  sim.Run();
  CHECK(order == std::vector<int>{10, 20, 30, 40, 50});
  CHECK(sim.Now() == 50);
  CHECK(sim.pending() == 0);
  CHECK(sim.executed() == 5);
}

TEST_CASE("Simulator: equal times run in insertion order", "[core]") {
  Simulator sim;
  std::vector<int> order;
  // Interleave two times so that ties are split across pushes and moves.
  for (int i = 0; i < 2000; ++i) {
    sim.ScheduleAt(i % 2 == 0 ? 1000 : 999, [&order, i] { order.push_back(i); });
  }
  sim.Run();
  std::vector<int> expected;
  for (int i = 1; i < 2000; i += 2) expected.push_back(i);
  for (int i = 0; i < 2000; i += 2) expected.push_back(i);
  CHECK(order == expected);
}

TEST_CASE("Simulator: an event scheduled for Now() runs after those already due", "[core]") {
  Simulator sim;
  std::vector<std::string> order;
  sim.ScheduleAt(5, [&] {
    order.push_back("a");
    sim.ScheduleAfter(0, [&] { order.push_back("a-child"); });
  });
  sim.ScheduleAt(5, [&] { order.push_back("b"); });
  sim.ScheduleAt(6, [&] { order.push_back("c"); });
  sim.Run();
  CHECK(order == std::vector<std::string>{"a", "b", "a-child", "c"});
}

TEST_CASE("Simulator: many events at one time stay FIFO while they reschedule", "[core]") {
  // 3000 events at t = 7 each reschedule themselves at t = 7 until 100000 have
  // run: a round robin, which also exercises dropping bucket 0's popped prefix.
  Simulator sim;
  std::vector<int> order;
  constexpr int kCount = 3000;
  constexpr int kTotal = 100000;
  struct Event {
    Simulator* sim;
    std::vector<int>* order;
    int label;
    void operator()() const {
      order->push_back(label);
      if (static_cast<int>(order->size()) + static_cast<int>(sim->pending()) < kTotal) {
        sim->ScheduleAfter(0, *this);
      }
    }
  };
  for (int i = 0; i < kCount; ++i) sim.ScheduleAt(7, Event{&sim, &order, i});
  sim.Run();
  REQUIRE(order.size() == kTotal);
  for (int i = 0; i < kTotal; ++i) REQUIRE(order[i] == i % kCount);
  CHECK(sim.Now() == 7);
}

TEST_CASE("Simulator: ScheduleAfter from inside events advances the clock", "[core]") {
  Simulator sim;
  std::vector<SimTime> times;
  std::function<void()> tick = [&] {
    times.push_back(sim.Now());
    if (times.size() < 4) sim.ScheduleAfter(uavsim::core::Milliseconds(2.5), tick);
  };
  sim.ScheduleAt(uavsim::core::Seconds(1.0), tick);
  sim.Run();
  CHECK(times == std::vector<SimTime>{1'000'000'000, 1'002'500'000, 1'005'000'000, 1'007'500'000});
}

TEST_CASE("Simulator: Cancel of a pending event", "[core]") {
  Simulator sim;
  int ran = 0;
  const EventId a = sim.ScheduleAt(10, [&] { ran += 1; });
  const EventId b = sim.ScheduleAt(20, [&] { ran += 10; });
  CHECK(a.valid());
  CHECK(a != b);
  CHECK(sim.IsPending(a));
  CHECK(sim.Cancel(a));
  CHECK_FALSE(sim.IsPending(a));
  CHECK(sim.pending() == 1);
  CHECK_FALSE(sim.Cancel(a));  // already cancelled: a no-op
  sim.Run();
  CHECK(ran == 10);
  CHECK(sim.executed() == 1);
  CHECK(sim.Now() == 20);
}

TEST_CASE("Simulator: Cancel after execution is a harmless no-op", "[core]") {
  Simulator sim;
  int ran = 0;
  const EventId a = sim.ScheduleAt(10, [&] { ++ran; });
  sim.Run();
  CHECK(ran == 1);
  CHECK_FALSE(sim.IsPending(a));
  CHECK_FALSE(sim.Cancel(a));
  CHECK(sim.pending() == 0);
}

TEST_CASE("Simulator: a default EventId refers to no event", "[core]") {
  Simulator sim;
  const EventId none;
  CHECK_FALSE(none.valid());
  CHECK_FALSE(sim.IsPending(none));
  CHECK_FALSE(sim.Cancel(none));
  sim.ScheduleAt(1, [] {});
  CHECK_FALSE(sim.IsPending(none));
  CHECK_FALSE(sim.Cancel(none));
  CHECK(sim.pending() == 1);
}

TEST_CASE("Simulator: a reused slot does not confuse old ids", "[core]") {
  Simulator sim;
  int ran_b = 0;
  const EventId a = sim.ScheduleAt(1, [] {});
  sim.Run();
  // b takes a's freed slot; a's id must not reach it.
  const EventId b = sim.ScheduleAt(2, [&] { ++ran_b; });
  CHECK(a != b);
  CHECK_FALSE(sim.IsPending(a));
  CHECK_FALSE(sim.Cancel(a));
  CHECK(sim.IsPending(b));
  // Same after a cancellation: c takes b's slot once b's entry has left.
  CHECK(sim.Cancel(b));
  sim.Run();
  const EventId c = sim.ScheduleAt(3, [] {});
  CHECK_FALSE(sim.Cancel(b));
  CHECK(sim.IsPending(c));
  sim.Run();
  CHECK(ran_b == 0);
  CHECK(sim.executed() == 2);
  // Many generations on the few slots in use: every stale id stays stale.
  std::vector<EventId> old_ids;
  for (int i = 0; i < 1000; ++i) {
    old_ids.push_back(sim.ScheduleAfter(1, [] {}));
    if (i % 3 == 0) sim.Cancel(old_ids.back());
    sim.Run();
  }
  const EventId live = sim.ScheduleAfter(1, [] {});
  for (const EventId& id : old_ids) {
    REQUIRE_FALSE(sim.IsPending(id));
    REQUIRE_FALSE(sim.Cancel(id));
  }
  CHECK(sim.IsPending(live));
}

TEST_CASE("Simulator: cancel from inside an event at the same time", "[core]") {
  Simulator sim;
  std::vector<std::string> order;
  EventId b;
  sim.ScheduleAt(5, [&] {
    order.push_back("a");
    CHECK(sim.Cancel(b));
  });
  b = sim.ScheduleAt(5, [&] { order.push_back("b"); });
  sim.ScheduleAt(5, [&] { order.push_back("c"); });
  sim.Run();
  CHECK(order == std::vector<std::string>{"a", "c"});
  CHECK(sim.executed() == 2);
}

TEST_CASE("Simulator: an event cannot cancel itself and is not pending while running", "[core]") {
  Simulator sim;
  EventId self;
  bool checked = false;
  self = sim.ScheduleAt(3, [&] {
    CHECK_FALSE(sim.IsPending(self));
    CHECK_FALSE(sim.Cancel(self));
    checked = true;
  });
  sim.Run();
  CHECK(checked);
  CHECK(sim.pending() == 0);
}

TEST_CASE("Simulator: RunUntil runs events at t_end and stops before later ones", "[core]") {
  Simulator sim;
  std::vector<SimTime> ran;
  for (SimTime t : {99, 100, 100, 101})
    sim.ScheduleAt(t, [&ran, &sim] { ran.push_back(sim.Now()); });
  sim.RunUntil(100);
  CHECK(ran == std::vector<SimTime>{99, 100, 100});
  CHECK(sim.Now() == 100);
  CHECK(sim.pending() == 1);

  // Scheduling at t_end after the run is allowed and runs next time.
  sim.ScheduleAt(100, [&ran, &sim] { ran.push_back(sim.Now()); });
  sim.RunUntil(100);
  CHECK(ran.size() == 4);

  // With nothing due, RunUntil only moves the clock.
  sim.RunUntil(100);
  sim.RunUntil(100);
  CHECK(sim.Now() == 100);
  sim.Run();
  CHECK(ran == std::vector<SimTime>{99, 100, 100, 100, 101});
  CHECK(sim.Now() == 101);

  Simulator empty;
  empty.RunUntil(uavsim::core::Seconds(3.0));
  CHECK(empty.Now() == uavsim::core::Seconds(3.0));
}

TEST_CASE("Simulator: an event scheduled after RunUntil below a peeked time runs first", "[core]") {
  // RunUntil(10) looks at the event at 20 without running it; a later event at
  // 15 must still come before it.
  Simulator sim;
  std::vector<SimTime> ran;
  auto record = [&ran, &sim] { ran.push_back(sim.Now()); };
  sim.ScheduleAt(20, record);
  sim.ScheduleAt(1 << 20, record);
  sim.RunUntil(10);
  sim.ScheduleAt(15, record);
  sim.ScheduleAt(10, record);
  sim.ScheduleAt(20, record);
  sim.Run();
  CHECK(ran == std::vector<SimTime>{10, 15, 20, 20, 1 << 20});
}

TEST_CASE("Simulator: Stop returns after the current event", "[core]") {
  Simulator sim;
  std::vector<int> order;
  sim.ScheduleAt(1, [&] { order.push_back(1); });
  sim.ScheduleAt(2, [&] {
    order.push_back(2);
    sim.Stop();
  });
  sim.ScheduleAt(2, [&] { order.push_back(3); });
  sim.ScheduleAt(4, [&] { order.push_back(4); });
  sim.RunUntil(10);
  CHECK(order == std::vector<int>{1, 2});
  CHECK(sim.Now() == 2);  // a stopped RunUntil does not advance to t_end
  CHECK(sim.pending() == 2);
  sim.Run();  // the stop request does not carry over
  CHECK(order == std::vector<int>{1, 2, 3, 4});
  CHECK(sim.Now() == 4);
}

TEST_CASE("Simulator: Stop outside a run has no effect", "[core]") {
  Simulator sim;
  int ran = 0;
  sim.ScheduleAt(1, [&] { ++ran; });
  sim.Stop();
  sim.Run();
  CHECK(ran == 1);
}

TEST_CASE("Simulator: scheduling in the past throws", "[core]") {
  Simulator sim;
  sim.ScheduleAt(100, [] {});
  sim.Run();
  REQUIRE(sim.Now() == 100);
  CHECK_THROWS_MATCHES(
      sim.ScheduleAt(99, [] {}), std::invalid_argument,
      Catch::Message("Simulator::ScheduleAt: time 99 ns is before Now() = 100 ns"));
  CHECK_THROWS_MATCHES(sim.ScheduleAfter(-1, [] {}), std::invalid_argument,
                       Catch::Message("Simulator::ScheduleAfter: delay -1 ns must be >= 0"));
  CHECK_THROWS_WITH(sim.ScheduleAfter(uavsim::core::kTimeMax, [] {}),
                    Catch::Contains("goes past the end of time"));
  CHECK_THROWS_MATCHES(
      sim.RunUntil(50), std::invalid_argument,
      Catch::Message("Simulator::RunUntil: end time 50 ns is before Now() = 100 ns"));
  CHECK(sim.pending() == 0);
  // A throwing call leaves the simulator usable.
  sim.ScheduleAfter(0, [] {});
  sim.ScheduleAt(uavsim::core::kTimeMax, [] {});
  CHECK(sim.pending() == 2);
  sim.Run();
  CHECK(sim.Now() == uavsim::core::kTimeMax);
}

TEST_CASE("Simulator: Run from inside an event throws", "[core]") {
  Simulator sim;
  bool threw = false;
  sim.ScheduleAt(1, [&] {
    try {
      sim.Run();
    } catch (const std::logic_error& e) {
      threw = std::string(e.what()) == "Simulator: Run/RunUntil called from inside an event";
    }
  });
  sim.Run();
  CHECK(threw);
}

TEST_CASE("Simulator: an exception from an event propagates and the run can resume", "[core]") {
  Simulator sim;
  std::vector<int> order;
  sim.ScheduleAt(1, [&] { order.push_back(1); });
  sim.ScheduleAt(2, [] { throw std::runtime_error("boom"); });
  sim.ScheduleAt(3, [&] { order.push_back(3); });
  CHECK_THROWS_WITH(sim.Run(), "boom");
  CHECK(sim.Now() == 2);
  CHECK(sim.executed() == 2);
  CHECK(sim.pending() == 1);
  sim.Run();
  CHECK(order == std::vector<int>{1, 3});
}

TEST_CASE("Simulator: callables of any size are run once and destroyed", "[core]") {
  auto token = std::make_shared<int>(0);
  std::array<double, 32> big{};  // 256 bytes: stored on the heap
  big[31] = 2.5;
  double seen = 0.0;
  {
    Simulator sim;
    sim.ScheduleAt(1, [token, &seen, big] { seen = big[31] + *token; });
    sim.ScheduleAt(2, [token] { ++*token; });
    const EventId cancelled =
        sim.ScheduleAt(3, [token, big] { *token += static_cast<int>(big[0]); });
    sim.ScheduleAt(4, [token] { ++*token; });               // left pending
    sim.ScheduleAt(4, [token, big] { *token += big[0]; });  // left pending, large
    CHECK(token.use_count() == 6);
    CHECK(sim.Cancel(cancelled));
    CHECK(token.use_count() == 5);  // a cancelled callable is destroyed at once
    sim.RunUntil(3);
    CHECK(token.use_count() == 3);  // run callables are destroyed after running
    CHECK(seen == 2.5);
    CHECK(*token == 1);
  }
  CHECK(token.use_count() == 1);  // the destructor destroyed the pending ones

  // Move-only callables, function pointers and mutable lambdas.
  Simulator sim;
  static int calls = 0;
  auto owned = std::make_unique<int>(41);
  int result = 0;
  sim.ScheduleAt(1, [p = std::move(owned), &result] { result = *p + 1; });
  sim.ScheduleAt(
      2, +[] { ++calls; });
  sim.ScheduleAt(3, [n = 0, &result]() mutable { result += ++n; });
  sim.Run();
  CHECK(result == 43);
  CHECK(calls == 1);
}

TEST_CASE("Simulator: cancelling most events keeps order and counts", "[core]") {
  // Enough cancels to sweep the cancelled entries out of the queue.
  Simulator sim;
  RngStream rng(7, "simulator_test/cancel");
  std::vector<std::pair<SimTime, int>> kept;  // (time, label), stable-sorted below
  std::vector<EventId> ids;
  std::vector<int> ran;
  constexpr int kEvents = 20000;
  std::vector<SimTime> times(kEvents);
  for (int i = 0; i < kEvents; ++i) {
    times[i] = static_cast<SimTime>(rng.UniformInt(5000));
    ids.push_back(sim.ScheduleAt(times[i], [&ran, i] { ran.push_back(i); }));
  }
  std::vector<bool> cancelled(kEvents, false);
  for (int n = 0; n < 16000; ++n) {
    const int i = static_cast<int>(rng.UniformInt(kEvents));
    CHECK(sim.Cancel(ids[i]) == !cancelled[i]);
    cancelled[i] = true;
  }
  std::size_t expected_pending = 0;
  for (int i = 0; i < kEvents; ++i) {
    if (!cancelled[i]) {
      kept.emplace_back(times[i], i);
      ++expected_pending;
    }
  }
  CHECK(sim.pending() == expected_pending);
  std::stable_sort(kept.begin(), kept.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  sim.Run();
  REQUIRE(ran.size() == kept.size());
  for (std::size_t k = 0; k < kept.size(); ++k) REQUIRE(ran[k] == kept[k].second);
  for (int i = 0; i < kEvents; ++i) REQUIRE_FALSE(sim.IsPending(ids[i]));
}

TEST_CASE("Simulator: cancelling most same-time events from inside one keeps FIFO", "[core]") {
  Simulator sim;
  std::vector<int> ran;
  std::vector<EventId> ids;
  constexpr int kEvents = 6000;
  sim.ScheduleAt(9, [&] {
    for (int i = 0; i < kEvents; ++i) {
      if (i % 7 != 0) CHECK(sim.Cancel(ids[i]));
    }
  });
  for (int i = 0; i < kEvents; ++i)
    ids.push_back(sim.ScheduleAt(9, [&ran, i] { ran.push_back(i); }));
  sim.Run();
  std::vector<int> expected;
  for (int i = 0; i < kEvents; i += 7) expected.push_back(i);
  CHECK(ran == expected);
  CHECK(sim.pending() == 0);
}

namespace {

// Random operations on a Simulator and on a reference model: a std::map keyed
// by (time, insertion number). Some events schedule a child when they run, at
// a delay derived from their label, so scheduling from inside events is
// checked too; every label's EventId is kept for random cancels.
class RandomizedHarness {
 public:
  void Schedule(SimTime t) {
    const int label = next_label_++;
    ids_.push_back(EventId());
    ids_[label] = sim_.ScheduleAt(t, Event{this, label});
    ref_keys_.push_back({t, ref_sequence_++});
    ref_[ref_keys_[label]] = label;
    REQUIRE(ref_next_label_++ == label);
  }

  bool Cancel(int label) {
    const bool cancelled = sim_.Cancel(ids_[label]);
    const bool ref_cancelled = ref_.erase(ref_keys_[label]) == 1;
    REQUIRE(cancelled == ref_cancelled);
    return cancelled;
  }

  void CheckPending(int label) const {
    REQUIRE(sim_.IsPending(ids_[label]) == (ref_.count(ref_keys_[label]) == 1));
  }

  void RunUntil(SimTime t_end) {
    sim_.RunUntil(t_end);
    while (!ref_.empty() && ref_.begin()->first.first <= t_end) RefExecute();
    ref_now_ = t_end;
    Compare();
  }

  void RunAll() {
    sim_.Run();
    while (!ref_.empty()) RefExecute();
    Compare();
  }

  SimTime Now() const { return sim_.Now(); }
  int labels() const { return next_label_; }
  std::uint64_t executed() const { return sim_.executed(); }

 private:
  struct Event {
    RandomizedHarness* h;
    int label;
    void operator()() const {
      h->log_.push_back(label);
      if (HasChild(label)) {
        const int child = h->next_label_++;
        h->ids_.push_back(EventId());
        h->ids_[child] = h->sim_.ScheduleAfter(ChildDelay(label), Event{h, child});
      }
    }
  };
  static bool HasChild(int label) { return label % 5 == 0; }
  static SimTime ChildDelay(int label) { return label % 7 == 0 ? 0 : (label % 11) * 37; }

  void RefExecute() {
    const auto it = ref_.begin();
    const int label = it->second;
    ref_now_ = it->first.first;
    ref_.erase(it);
    ref_log_.push_back(label);
    if (HasChild(label)) {
      const int child = ref_next_label_++;
      ref_keys_.push_back({ref_now_ + ChildDelay(label), ref_sequence_++});
      ref_[ref_keys_[child]] = child;
    }
  }

  void Compare() {
    REQUIRE(log_ == ref_log_);
    REQUIRE(sim_.Now() == ref_now_);
    REQUIRE(sim_.pending() == ref_.size());
    REQUIRE(next_label_ == ref_next_label_);
  }

  Simulator sim_;
  std::vector<EventId> ids_;
  std::vector<int> log_;
  int next_label_ = 0;

  std::map<std::pair<SimTime, std::uint64_t>, int> ref_;
  std::vector<std::pair<SimTime, std::uint64_t>> ref_keys_;
  std::vector<int> ref_log_;
  std::uint64_t ref_sequence_ = 0;
  int ref_next_label_ = 0;
  SimTime ref_now_ = 0;
};

}  // namespace

namespace {

struct OperationMix {
  double schedule, cancel, check;  // probabilities; the rest is RunUntil
};

// Returns the number of successful cancels.
int RandomOperations(RandomizedHarness& h, RngStream& rng, int count, OperationMix mix) {
  int cancels = 0;
  for (int op = 0; op < count; ++op) {
    const double u = rng.Uniform();
    if (u < mix.schedule) {
      // Delays with many ties, medium spreads and rare far-future times.
      const double kind = rng.Uniform();
      SimTime delay;
      if (kind < 0.4) {
        delay = static_cast<SimTime>(rng.UniformInt(4));
      } else if (kind < 0.9) {
        delay = static_cast<SimTime>(rng.UniformInt(1000));
      } else if (kind < 0.99) {
        delay = static_cast<SimTime>(rng.UniformInt(uavsim::core::Seconds(10.0)));
      } else {
        delay = static_cast<SimTime>(rng.UniformInt(std::uint64_t{1} << 50));
      }
      h.Schedule(h.Now() + delay);
    } else if (u < mix.schedule + mix.cancel) {
      // Mostly recent labels, which are likely still pending; any label may be stale.
      if (h.labels() > 0) {
        const int back = static_cast<int>(
            rng.UniformInt(rng.Uniform() < 0.8 ? std::min(h.labels(), 50) : h.labels()));
        cancels += h.Cancel(h.labels() - 1 - back);
      }
    } else if (u < mix.schedule + mix.cancel + mix.check) {
      if (h.labels() > 0) h.CheckPending(static_cast<int>(rng.UniformInt(h.labels())));
    } else {
      const SimTime step = rng.Uniform() < 0.95 ? static_cast<SimTime>(rng.UniformInt(300))
                                                : static_cast<SimTime>(rng.UniformInt(1 << 30));
      h.RunUntil(h.Now() + step);
    }
  }
  return cancels;
}

}  // namespace

TEST_CASE("Simulator: 100k random operations match a reference queue", "[core]") {
  RandomizedHarness h;
  RngStream rng(2024, "simulator_test/random");
  // A balanced mix, then one heavy in cancels, then a storm of cancels that
  // makes the queue sweep out cancelled entries, then the balanced mix again.
  const int cancels_balanced = RandomOperations(h, rng, 40000, {0.5, 0.2, 0.1});
  const int cancels_heavy = RandomOperations(h, rng, 30000, {0.5, 0.45, 0.02});
  // A storm: 10000 events in the next second, 8000 of them cancelled.
  const int first = h.labels();
  for (int i = 0; i < 10000; ++i) {
    h.Schedule(h.Now() + static_cast<SimTime>(rng.UniformInt(uavsim::core::Seconds(1.0))));
  }
  for (int i = 0; i < 8000; ++i) h.Cancel(first + static_cast<int>(rng.UniformInt(10000)));
  RandomOperations(h, rng, 30000, {0.5, 0.2, 0.1});
  h.RunAll();
  CHECK(cancels_balanced > 1000);
  CHECK(cancels_heavy > 4000);
  CHECK(h.executed() > 30000);
}
