#include "core/interrupt.h"

#include <signal.h>
#include <atomic>

#include <csignal>

namespace uavsim::core {
namespace {

std::atomic<bool> g_interrupt{false};
static_assert(std::atomic<bool>::is_always_lock_free,
              "a signal handler may store only to lock-free atomics");

extern "C" void OnTerminationSignal(int) { RequestInterrupt(); }

}  // namespace

void InstallInterruptHandlers() {
  struct sigaction sa {};
  sa.sa_handler = OnTerminationSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

namespace {
void MaskTermination(int how) {
  sigset_t termination;
  sigemptyset(&termination);
  sigaddset(&termination, SIGINT);
  sigaddset(&termination, SIGTERM);
  sigprocmask(how, &termination, nullptr);
}
}  // namespace

void TakeOverTerminationSignals() {
  InstallInterruptHandlers();
  MaskTermination(SIG_UNBLOCK);
}

void BlockTerminationSignals() { MaskTermination(SIG_BLOCK); }

void RequestInterrupt() noexcept { g_interrupt.store(true, std::memory_order_relaxed); }

void ClearInterrupt() noexcept { g_interrupt.store(false, std::memory_order_relaxed); }

bool InterruptRequested() noexcept { return g_interrupt.load(std::memory_order_relaxed); }

void ThrowIfInterrupted() {
  if (InterruptRequested()) throw Interrupted();
}

}  // namespace uavsim::core
