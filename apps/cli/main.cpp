// The uavsim command line (DESIGN.md "Command line"): finds the command in
// the table (cli.h), parses its options, runs it. Errors from bad input are
// caught here once: one line on stderr, exit code 2.
#include <signal.h>

#include <cstdio>
#include <iostream>
#include <new>
#include <string>

#include "apps/cli/cli.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "pipeline/edge/scripted_edge.h"
#include "sim/version.h"

namespace {

using namespace uavsim::cli;
using uavsim::core::UsageError;

// `uavsim --help`: the commands from the table.
std::string MainHelp() {
  std::string out =
      "uavsim: discrete-event network and sensing simulator for edge-assisted multimodal UAV "
      "localization\n"
      "\n"
      "usage: uavsim COMMAND [OPTIONS]\n"
      "\n"
      "commands:\n";
  for (const Command& c : Commands()) {
    char line[256];
    std::snprintf(line, sizeof line, "  %-26s %s\n", c.usage.c_str(), c.summary.c_str());
    out += line;
  }
  return out +
         "\n"
         "options: --help (also after a command), --version, --quiet (every command)\n"
         "exit codes: 0 ok, 1 failure while running, 2 bad input or usage, 130 interrupted\n";
}

int Main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << MainHelp();
    return kExitBadInput;
  }
  const std::string cmd = argv[1];
  if (cmd == "--help" || cmd == "-h" || cmd == "help") return std::cout << MainHelp(), kExitOk;
  if (cmd == "--version") {
    std::cout << "uavsim " << uavsim::sim::Version();
    if (*uavsim::sim::GitHash()) std::cout << " (" << uavsim::sim::GitHash() << ")";
    std::cout << "\n";
    return kExitOk;
  }
  for (const Command& c : Commands()) {
    if (c.name != cmd) continue;
    if (c.precheck) c.precheck(argc, argv);
    const ParsedArgs a = Parse(c, argc, argv, 2);
    if (a.Has("--help")) return std::cout << c.help(), kExitOk;
    return c.run(a, argc, argv);
  }
  throw UsageError("uavsim: unknown command '" + cmd + "' (see uavsim --help)");
}

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
    const int rc = Main(argc, argv);
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
