// The discrete-event core: a simulated clock in integer nanoseconds and a queue
// of scheduled callables (ns-3's Simulator, one object per run, no globals).
//
// Ordering: events run in increasing time; events at equal times run in the
// order they were scheduled (strict FIFO).
// Determinism: no randomness, no wall clock and no threads are involved, so the
// same calls in the same order give the same execution order, bit for bit.
// Threads: a Simulator is not thread-safe; use one per thread.
// Cost: scheduling and cancelling are O(1) amortised and allocate nothing for
// callables up to kInlineCallableBytes once the simulator has warmed up;
// running an event is O(1) amortised (a radix heap with 8 levels of 8-bit
// digits). `uavsim bench events` measures it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/time.h"

namespace uavsim::core {

// A kept handle to a scheduled event, for Simulator::Cancel and IsPending.
// A default-constructed id refers to no event. An id names a storage slot and
// the slot's 64-bit generation counter, which advances whenever the slot's
// event runs or is cancelled and never wraps: the id of an event that has run
// or was cancelled stays stale after its slot is reused, so a late Cancel can
// never remove another event.
class EventId {
 public:
  EventId() = default;

  // False only for a default-constructed id (a stale id is still valid()).
  bool valid() const { return generation_ != 0; }

  friend bool operator==(const EventId& a, const EventId& b) {
    return a.generation_ == b.generation_ && a.slot_ == b.slot_;
  }
  friend bool operator!=(const EventId& a, const EventId& b) { return !(a == b); }

 private:
  friend class Simulator;
  EventId(std::uint64_t generation, std::uint32_t slot) : generation_(generation), slot_(slot) {}

  std::uint64_t generation_ = 0;  // odd: the slot's generation while the event is pending
  std::uint32_t slot_ = 0;
};

namespace simulator_detail {

enum class CallableOp { kInvokeAndDestroy, kDestroy };
using CallableThunk = void (*)(void* storage, CallableOp op);

// Type-erased operations on a callable constructed in place in a slot.
template <typename Fn>
struct InlineCallable {
  static void Call(void* storage, CallableOp op) {
    Fn* fn = std::launder(static_cast<Fn*>(storage));
    struct Destroyer {
      Fn* fn;
      ~Destroyer() { fn->~Fn(); }
    } destroyer{fn};
    if (op == CallableOp::kInvokeAndDestroy) std::invoke(*fn);
  }
};

// The same for a callable too large for a slot: the slot holds an owning Fn*.
template <typename Fn>
struct HeapCallable {
  static void Call(void* storage, CallableOp op) {
    std::unique_ptr<Fn> fn(*std::launder(static_cast<Fn**>(storage)));
    if (op == CallableOp::kInvokeAndDestroy) std::invoke(*fn);
  }
};

}  // namespace simulator_detail

class Simulator {
 public:
  // Callables up to this size and alignment are stored inline, without a heap
  // allocation (a lambda capturing up to six pointers, or a std::function).
  // Larger ones are moved to the heap, once, when scheduled.
  static constexpr std::size_t kInlineCallableBytes = 48;
  static constexpr std::size_t kInlineCallableAlign = 16;

  Simulator();
  // Destroys the callables of pending events without running them.
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  // The current simulated time: 0 before the first run, the time of the event
  // being executed inside an event.
  SimTime Now() const { return now_; }

  // Schedules `fn` (any callable invocable as fn(); its result is discarded) to
  // run at absolute time t_ns. Scheduling at Now() is allowed, also from inside
  // an event: the new event runs after those already scheduled for Now().
  // Throws std::invalid_argument if t_ns < Now(), std::length_error if 2^32 - 1
  // events are already held. If copying or moving `fn` throws, nothing is
  // scheduled and the exception propagates.
  template <typename F>
  EventId ScheduleAt(SimTime t_ns, F&& fn);

  // Schedules `fn` at Now() + delay_ns. Throws std::invalid_argument if
  // delay_ns < 0 or if Now() + delay_ns would exceed kTimeMax.
  template <typename F>
  EventId ScheduleAfter(SimTime delay_ns, F&& fn);

  // Cancels a pending event: its callable is destroyed now, without running.
  // Returns true if the event was pending; false (and does nothing) if it has
  // run, is running, was cancelled, or `id` is default-constructed.
  bool Cancel(EventId id);

  // True if the event is scheduled and has neither run nor been cancelled.
  // False for the event currently executing.
  bool IsPending(EventId id) const;

  // Runs events in order until none is left or Stop() is called. Afterwards
  // Now() is the time of the last event executed.
  // Throws std::logic_error if called from inside an event. An exception thrown
  // by an event propagates out of the run; that event counts as executed and
  // the Simulator stays usable, with Now() at that event's time.
  void Run();

  // Runs every event with time <= t_end_ns (including events scheduled during
  // the run), in order, then sets Now() to t_end_ns. If Stop() is called, it
  // returns after the current event and Now() stays at that event's time.
  // Throws std::invalid_argument if t_end_ns < Now(), std::logic_error if
  // called from inside an event.
  void RunUntil(SimTime t_end_ns);

  // Called from inside an event: the current Run/RunUntil returns once that
  // event has finished; later events stay pending. Each run clears the request
  // when it starts (as ns-3 does), so Stop() outside a run has no effect.
  void Stop() { stop_requested_ = true; }

  // Events scheduled and neither run nor cancelled.
  std::size_t pending() const { return pending_; }
  // Events executed since construction (an event that threw counts).
  std::uint64_t executed() const { return executed_; }

 private:
  using CallableThunk = simulator_detail::CallableThunk;

  // One cache line: the inline callable, its thunk and a generation counter
  // that is odd exactly while the slot holds a pending event. A free slot keeps
  // the index of the next free slot in `storage`.
  struct alignas(64) Slot {
    alignas(kInlineCallableAlign) unsigned char storage[kInlineCallableBytes];
    CallableThunk thunk;
    std::uint64_t generation;
  };
  static_assert(sizeof(Slot) == 64, "a slot should fill one cache line");

  // A queue entry owns its slot until it is popped: a cancelled event's slot
  // (even generation) is freed only when its entry leaves the queue.
  struct QueueEntry {
    SimTime time;
    std::uint32_t slot;
  };

  static constexpr int kChunkBits = 10;  // slots are allocated 1024 at a time
  static constexpr std::uint32_t kChunkSize = 1u << kChunkBits;
  static constexpr std::uint32_t kNoSlot = 0xffffffffu;
  // Radix heap with kDigitBits-bit digits: bucket 0 holds the times equal to
  // the last one popped, then one bucket per (level, digit) of the highest
  // digit in which a time differs from it.
  static constexpr int kDigitBits = 8;
  static constexpr int kLevels = (64 + kDigitBits - 1) / kDigitBits;
  static constexpr int kBuckets = 1 + (kLevels << kDigitBits);
  static constexpr int kMaskWords = (kBuckets + 63) / 64;
  static_assert(kMaskWords <= 64, "the summary word covers at most 64 mask words");

  Slot& SlotAt(std::uint32_t index) const {
    return chunks_[index >> kChunkBits][index & (kChunkSize - 1)];
  }
  std::uint32_t AcquireSlot();
  void ReleaseSlot(std::uint32_t index);
  void CheckScheduleTime(SimTime t_ns) const {
    if (t_ns < now_) ThrowPastTime(t_ns);
  }
  [[noreturn]] void ThrowPastTime(SimTime t_ns) const;
  [[noreturn]] void ThrowBadDelay(SimTime delay_ns) const;
  EventId Enqueue(SimTime t_ns, std::uint32_t index);
  void RunLoop(SimTime t_end_ns, bool advance_to_end);

  // Radix heap over event times with FIFO buckets, implemented in the .cpp.
  void QueuePush(SimTime time, std::uint32_t slot);
  const QueueEntry& QueueMin();
  QueueEntry QueuePopMin();
  int LowestBucket() const;
  void MarkBucket(int b);
  void UnmarkBucket(int b);
  void PurgeCancelled();

  SimTime now_ = 0;
  std::size_t pending_ = 0;
  std::uint64_t executed_ = 0;
  bool running_ = false;
  bool stop_requested_ = false;

  // Slab of slots in fixed-size chunks, so a slot never moves while its
  // callable runs, even if that callable schedules more events.
  std::vector<std::unique_ptr<Slot[]>> chunks_;
  std::uint32_t slot_count_ = 0;
  std::uint32_t free_head_ = kNoSlot;

  std::unique_ptr<std::vector<QueueEntry>[]> buckets_;  // kBuckets of them
  std::size_t bucket0_head_ = 0;                        // bucket 0 is a FIFO: popped from here
  std::uint64_t bucket_mask_[kMaskWords] = {};          // bit b set iff bucket b has entries
  std::uint64_t bucket_summary_ = 0;                    // bit w set iff bucket_mask_[w] != 0
  SimTime last_time_ = 0;                               // time of the last entry popped
  std::size_t queued_ = 0;                              // entries, including cancelled ones
  std::size_t cancelled_ = 0;                           // entries whose event was cancelled
  QueueEntry min_cache_{};  // first entry of least time, while min_cached_
  bool min_cached_ = false;
};

template <typename F>
EventId Simulator::ScheduleAt(SimTime t_ns, F&& fn) {
  using Fn = std::decay_t<F>;
  static_assert(std::is_invocable_v<Fn&>, "an event must be callable with no arguments");
  CheckScheduleTime(t_ns);
  const std::uint32_t index = AcquireSlot();
  Slot& slot = SlotAt(index);
  if constexpr (sizeof(Fn) <= kInlineCallableBytes && alignof(Fn) <= kInlineCallableAlign) {
    try {
      ::new (static_cast<void*>(slot.storage)) Fn(std::forward<F>(fn));
    } catch (...) {
      ReleaseSlot(index);
      throw;
    }
    slot.thunk = &simulator_detail::InlineCallable<Fn>::Call;
  } else {
    Fn* on_heap = nullptr;
    try {
      on_heap = new Fn(std::forward<F>(fn));
    } catch (...) {
      ReleaseSlot(index);
      throw;
    }
    ::new (static_cast<void*>(slot.storage)) Fn*(on_heap);
    slot.thunk = &simulator_detail::HeapCallable<Fn>::Call;
  }
  return Enqueue(t_ns, index);
}

template <typename F>
EventId Simulator::ScheduleAfter(SimTime delay_ns, F&& fn) {
  if (delay_ns < 0 || delay_ns > kTimeMax - now_) ThrowBadDelay(delay_ns);
  return ScheduleAt(now_ + delay_ns, std::forward<F>(fn));
}

}  // namespace uavsim::core
