// uavsim-light: the command line without LibTorch (it loads in a few
// milliseconds where uavsim-main takes 0.5 s or more). It runs `--version`,
// `--help` (of every command), `validate` and `report` itself, and runs
// uavsim-main in its place, with the same arguments, for every other
// command and for a validate whose models only loading can check (cli.h).
// The `uavsim` launcher starts it. Its link has no LibTorch: a source of
// it that comes to need LibTorch fails the build (apps/CMakeLists.txt).
#include <errno.h>
#include <limits.h>
#include <unistd.h>

#include <cstring>
#include <iostream>
#include <string>

#include "apps/cli/validate.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "sim/model_check.h"

namespace {

using namespace uavsim;

// As in uavsim-main (main.cpp): the handlers before any initialiser.
void TakeOverFirst(int, char**, char**) { core::TakeOverTerminationSignals(); }
__attribute__((section(".preinit_array"),
               used)) void (*const kTakeOverFirst)(int, char**, char**) = TakeOverFirst;

// Runs uavsim-main, beside this program, in its place: the same process
// (the PID a user or a scheduler holds), arguments and environment. A
// termination request that came here first is answered here; one that
// comes during the switch waits, blocked, for uavsim-main's handlers.
[[noreturn]] void HandToMain(char** argv) {
  core::BlockTerminationSignals();
  core::ThrowIfInterrupted();
  static const char kName[] = "uavsim-main";
  char path[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", path, sizeof path - sizeof kName);
  if (n <= 0)
    throw std::runtime_error(std::string("cannot find its own executable: ") +
                             std::strerror(errno));
  std::string exe(path, static_cast<std::size_t>(n));
  exe = exe.substr(0, exe.rfind('/') + 1) + kName;
  execv(exe.c_str(), argv);
  throw std::runtime_error("cannot run " + exe + ": " + std::strerror(errno));
}

int HandOn(const cli::ParsedArgs&, int, char** argv) { HandToMain(argv); }

}  // namespace

namespace uavsim::cli {

int RunRunCommand(const ParsedArgs& a, int argc, char** argv) { return HandOn(a, argc, argv); }
int RunSweepCommand(const ParsedArgs& a, int argc, char** argv) { return HandOn(a, argc, argv); }
int RunTrainCommand(const ParsedArgs& a, int argc, char** argv) { return HandOn(a, argc, argv); }
int RunDatasetCommand(const ParsedArgs& a, int argc, char** argv) { return HandOn(a, argc, argv); }
int RunReproduceCommand(const ParsedArgs& a, int argc, char** argv) {
  return HandOn(a, argc, argv);
}
int RunBenchCommand(const ParsedArgs& a, int argc, char** argv) { return HandOn(a, argc, argv); }

// Validate here unless a scenario's models need loading: then uavsim-main
// validates every file, before a line is printed here. A file that does
// not load is left to the validation proper, which reports it.
int RunValidateCommand(const ParsedArgs& a, int, char** argv) {
  for (const std::string& file : a.positional) {
    try {
      if (sim::CheckModelFiles(sim::LoadScenario(file, Overrides(a)), file)) HandToMain(argv);
    } catch (const core::ConfigError&) {
    }
  }
  return ValidateScenarios(a, [](const sim::Scenario& s, const std::string& file, bool) {
    sim::CheckModelFiles(s, file);
  });
}

}  // namespace uavsim::cli

int main(int argc, char** argv) { return uavsim::cli::RunMain(argc, argv); }
