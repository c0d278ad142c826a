// `uavsim validate` as typed: its usage, options and help (its body:
// apps/cli/validate.cpp; the command table: cli.h).
#include "apps/cli/cli.h"

namespace uavsim::cli {
namespace {

const char* kHelp =
    "usage: uavsim validate SCENARIO.json [MORE.json]... [--set /json/pointer=value]...\n"
    "                       [--record camera,lidar,radar,mcap] [--resolved] [--quiet]\n"
    "\n"
    "Checks each SCENARIO.json strictly (unknown keys, types, ranges, references, files,\n"
    "meshes, the trained model's manifest and checksums, resource limits: rays and\n"
    "memory against this machine's). Exit 0 if all are valid, else exit 2 with one line\n"
    "on stderr per invalid file:\n"
    "  FILE: /json/pointer: expected ..., got ...\n"
    "\n"
    "  --set P=V     override the value at JSON pointer P (V is JSON, or a bare string),\n"
    "                in every file\n"
    "  --resolved    print the scenario with every default filled, as JSON, on stdout\n"
    "                (one file only)\n"
    "  --record LIST also say how many bytes `run --record LIST` would write at most\n"
    "  --quiet       print nothing on success\n";

std::string Help() { return kHelp; }

}  // namespace

Command ValidateCommand() {
  return {"validate",
          "validate SCENARIO.json",
          "check a scenario; exit 0, or exit 2 with FILE: /json/pointer: message",
          {{"--set", true}, {"--record", true}, {"--resolved", false}},
          Help,
          RunValidateCommand};
}

}  // namespace uavsim::cli
