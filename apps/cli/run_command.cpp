// `uavsim run` as typed: its usage, options and help (its body:
// apps/cli/run.cpp; the command table: cli.h).
#include "apps/cli/cli.h"

namespace uavsim::cli {
namespace {

const char* kHelp =
    "usage: uavsim run SCENARIO.json [--out DIR] [--seed N] [--duration S] [--record "
    "camera,lidar,radar,mcap]\n"
    "                               [--set /json/pointer=value]... [--trace DIR | --replay DIR]\n"
    "                               [--force] [--quiet] [--verbose]\n"
    "\n"
    "Runs the scenario and writes DIR (default runs/NAME-sSEED): manifest.json, truth.csv,\n"
    "estimates.csv, metrics.json (RMSE per method, packets, data rates), packets.csv,\n"
    "rate_snr.csv/.png, world_top.csv and layout.csv (the map), report.html (figures and\n"
    "tables: open it in a browser) with report/, and recorded frames. The directory\n"
    "appears only when the run is complete. Methods (/pipeline/methods): uavloc (the\n"
    "paper's pipeline), uavloc_camera/_lidar/_radar (it on one modality), uavloc_anchored\n"
    "(our anchored head), anchor_track (its filter alone), ekf (the classical baseline).\n"
    "The learned ones use the model /pipeline/model names (\"default\": the one shipped\n"
    "for scenarios/default.json; `uavsim train` makes others).\n"
    "\n"
    "  --out DIR       run directory (refused if it exists, unless --force)\n"
    "  --seed N        override the scenario's seed (same as --set /seed=N)\n"
    "  --duration S    override duration_s (same as --set /duration_s=S)\n"
    "  --record LIST   record raw frames of these modalities under DIR/frames/; mcap:\n"
    "                  DIR/recording.mcap, every sensor, the world, truth, estimates and\n"
    "                  uplink in one file for Foxglove (docs/recordings.md)\n"
    "  --set P=V       override the value at JSON pointer P\n"
    "  --trace DIR     also write what the sensing nodes sent to DIR/KEY.trace (KEY: a hash\n"
    "                  of everything that determines sensing; not links, methods or beams)\n"
    "  --replay DIR    take the nodes' messages from DIR/KEY.trace instead of sensing: the\n"
    "                  same outputs, byte for byte, in a fraction of the time (docs/speed.md)\n"
    "  --force         replace DIR if it exists\n"
    "  --quiet         no progress or summary output\n"
    "  --verbose       a failing TorchScript method's whole traceback after its line\n";

std::string Help() { return kHelp; }

}  // namespace

Command RunCommand() {
  return {"run",
          "run SCENARIO.json",
          "run a scenario and write its run directory",
          {{"--out", true},
           {"--seed", true},
           {"--duration", true},
           {"--record", true},
           {"--set", true},
           {"--trace", true},
           {"--replay", true},
           {"--force", false},
           {"--verbose", false}},
          Help,
          RunRunCommand};
}

}  // namespace uavsim::cli
