// The command line's two programs (apps/cli/cli.h): --version, --help,
// validate and report run without loading LibTorch (the dynamic loader's
// own log, LD_DEBUG=files, lists every library a process maps); every other
// command, and a validate whose model only loading checks, runs in
// uavsim-main, LibTorch loaded, under the same PID.
#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "test_support.h"

using uavsim::testing::RunCli;
using uavsim::testing::RunProgram;
using uavsim::testing::TempDir;

namespace {

const std::string kDefault = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/default.json";

// `uavsim ARGS` with the dynamic loader logging the files it loads.
uavsim::testing::CliResult Logged(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {"/usr/bin/env", "LD_DEBUG=files", UAVSIM_CLI};
  argv.insert(argv.end(), args.begin(), args.end());
  return RunProgram(argv);
}

bool LoadsTorch(const std::string& loader_log) {
  return loader_log.find("libtorch_cpu.so") != std::string::npos;
}

}  // namespace

TEST_CASE("CLI: --version, --help, validate and report load no LibTorch; the rest does", "[sim]") {
  const std::string dir = TempDir("light");
  const std::string run = dir + "/run";
  // A run to report on (it needs LibTorch: its methods run the model).
  const auto made = Logged({"run", kDefault, "--duration", "1", "--out", run, "--quiet"});
  INFO(made.err.substr(0, 2000));
  REQUIRE(made.exit_code == 0);
  CHECK(LoadsTorch(made.err));  // the log shows LibTorch where it is loaded
  for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
           {"--version"},
           {"--help"},
           {"run", "--help"},
           {"train", "--help"},
           {"validate", kDefault},
           {"validate", kDefault, "--set", "/pipeline/methods=[\"ekf\"]", "--resolved"},
           {"report", run}}) {
    const auto r = Logged(args);
    INFO(args[0] << " " << (args.size() > 1 ? args[1] : ""));
    CHECK(r.exit_code == 0);
    CHECK_FALSE(LoadsTorch(r.err));
    CHECK_FALSE(r.out.empty());
  }
  // The help of a command the light program does not run is the full
  // program's: the variants' list of train's help included.
  const auto train_help = RunCli({"train", "--help"});
  CHECK_THAT(train_help.out, Catch::Contains("variants (--variant"));
  // Bad input is refused there as in the full program: one line, exit 2.
  const auto bad = Logged({"validate", kDefault, "--set", "/duration_s=-1"});
  CHECK(bad.exit_code == 2);
  CHECK_FALSE(LoadsTorch(bad.err));
  CHECK_THAT(bad.err, Catch::Contains(kDefault + ": /duration_s: "));
}
