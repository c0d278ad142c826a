// The uavsim command line (DESIGN.md "Command line"): finds the command in
// the table (cli.h), parses its options, runs it. Errors from bad input are
// caught here once: one line on stderr, exit code 2.
#include <signal.h>

#include <iostream>
#include <new>

#include "apps/cli/cli.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "pipeline/edge/scripted_edge.h"

namespace {

using namespace uavsim::cli;
using uavsim::core::UsageError;

// The handlers go in before any shared library's initialisers run
// (LibTorch's take about half a second, more on a loaded machine): a
// SIGINT or SIGTERM from a command's first moments gets exit 130 and the
// documented line, not the default action's 143. Only the dynamic
// loader's work comes before a program's .preinit_array; the launcher
// (launcher.cpp) blocks the two signals over it, so they are unblocked
// here, once the handlers are in: one that came meanwhile is delivered now.
void InstallHandlersFirst(int, char**, char**) {
  uavsim::core::InstallInterruptHandlers();
  sigset_t termination;
  sigemptyset(&termination);
  sigaddset(&termination, SIGINT);
  sigaddset(&termination, SIGTERM);
  sigprocmask(SIG_UNBLOCK, &termination, nullptr);
}
__attribute__((section(".preinit_array"),
               used)) void (*const kInstallHandlersFirst)(int, char**,
                                                          char**) = InstallHandlersFirst;

}  // namespace

int main(int argc, char** argv) {
  try {
    uavsim::core::InstallInterruptHandlers();  // again: a library's initialiser may have reset them
    uavsim::core::ThrowIfInterrupted();        // a request during the libraries' initialisers
    const int rc = RunCommandLine(argc, argv);
    // A request the command did not poll for (it came during its last
    // steps): answered like any other.
    uavsim::core::ThrowIfInterrupted();
    return rc;
  } catch (const uavsim::core::ConfigError& e) {
    std::cerr << e.what() << "\n";
    return kExitBadInput;
  } catch (const UsageError& e) {
    std::cerr << e.what() << "\n";
    return kExitBadInput;
  } catch (const uavsim::core::Interrupted&) {
    std::cerr << "uavsim: interrupted; nothing half-written is left under a final name\n";
    return kExitInterrupted;
  } catch (const std::bad_alloc&) {
    std::cerr << "uavsim: out of memory\n";
    return kExitFailure;
  } catch (const uavsim::pipeline::ScriptedEdgeFailure& e) {
    std::cerr << "uavsim: " << e.what() << "\n";
    if (Verbose()) std::cerr << e.traceback() << "\n";
    return kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << "uavsim: " << e.what() << "\n";
    return kExitFailure;
  }
}
