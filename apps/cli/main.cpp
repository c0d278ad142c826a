// uavsim-main, the program proper of the command line (DESIGN.md "Command
// line"): every command, LibTorch loaded. The `uavsim` launcher runs it in
// its place, or uavsim-light does for a command it hands on (cli.h).
#include <string>

#include "apps/cli/cli.h"
#include "core/interrupt.h"
#include "pipeline/edge/scripted_edge.h"

namespace {

// The handlers go in before any shared library's initialisers run
// (LibTorch's take about half a second, more on a loaded machine): a
// SIGINT or SIGTERM from a command's first moments gets exit 130 and the
// documented line, not the default action's 143. Only the dynamic
// loader's work comes before a program's .preinit_array; the launcher
// (launcher.cpp) blocks the two signals over it.
void TakeOverFirst(int, char**, char**) { uavsim::core::TakeOverTerminationSignals(); }
__attribute__((section(".preinit_array"),
               used)) void (*const kTakeOverFirst)(int, char**, char**) = TakeOverFirst;

// A failing TorchScript method's whole traceback, with --verbose.
std::string Traceback(const std::exception& e) {
  const auto* failure = dynamic_cast<const uavsim::pipeline::ScriptedEdgeFailure*>(&e);
  return failure && uavsim::cli::Verbose() ? failure->traceback() : "";
}

}  // namespace

int main(int argc, char** argv) { return uavsim::cli::RunMain(argc, argv, Traceback); }
