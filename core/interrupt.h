// Termination requests (SIGINT/SIGTERM), process-wide. Long work polls them
// at small units (a block of rays, an image row, a detection) so a signal is
// honoured promptly even inside one heavy capture; the caller that owns the
// output (a run, a training, a sweep) then removes what it staged.
//
// Thread-safe: any thread may poll; the flag is a lock-free atomic, so the
// signal handler only stores to it.
#pragma once

#include <stdexcept>

namespace uavsim::core {

// Raised by ThrowIfInterrupted once a termination request has arrived.
struct Interrupted : std::runtime_error {
  Interrupted() : std::runtime_error("interrupted") {}
};

// Installs SIGINT/SIGTERM handlers that call RequestInterrupt.
void InstallInterruptHandlers();

// A program started with SIGINT and SIGTERM blocked (the `uavsim`
// launcher, apps/cli/launcher.cpp, blocks them over the dynamic loader's
// work) takes them over: installs the handlers, then unblocks them, so one
// that came meanwhile is delivered now.
void TakeOverTerminationSignals();

// Blocks SIGINT and SIGTERM again, before this process runs another
// program in its place (execv keeps them pending for it).
void BlockTerminationSignals();

// Records a termination request. Async-signal-safe.
void RequestInterrupt() noexcept;

// Forgets a request once it has been handled, for a caller that goes on
// (tests that check each stage polls).
void ClearInterrupt() noexcept;

// Whether a termination request has arrived (relaxed load: cheap to poll).
bool InterruptRequested() noexcept;

// Throws Interrupted if a termination request has arrived.
void ThrowIfInterrupted();

}  // namespace uavsim::core
