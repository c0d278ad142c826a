// `uavsim report` as typed: its usage, options and help (its body:
// apps/cli/report.cpp; the command table: cli.h).
#include "apps/cli/cli.h"

namespace uavsim::cli {
namespace {

const char* kHelp =
    "usage: uavsim report DIR [--quiet]\n"
    "\n"
    "Redraws the report of a run directory (report.html, report/, rate_snr.png) or of a\n"
    "finished sweep folder (summary.csv, aggregate.csv, plots/, report.html) from the\n"
    "files already there, without simulating anything: after a change of style, or for a\n"
    "directory made by an older uavsim (figures whose input file it lacks say so).\n"
    "For a folder of uavsim reproduce (claims.csv, the artefact CSVs, report.md: what\n"
    "docs/paper keeps) it redraws the verdicts from claims.csv with this binary's rules,\n"
    "training nothing: claims.csv and the verdict sections of report.md/report.html.\n"
    "Open DIR/report.html in a browser; it needs no network access.\n"
    "\n"
    "  --quiet   print nothing on success (warnings about figures not drawn still go to\n"
    "            stderr)\n"
    "exit codes: 0 written, 2 DIR is neither a run directory, a finished sweep nor a\n"
    "reproduction, or one of its files is malformed\n";

std::string Help() { return kHelp; }

}  // namespace

Command ReportCommand() {
  return {"report", "report DIR", "redraw a run's or a sweep's report.html from its files",
          {},       Help,         RunReportCommand};
}

}  // namespace uavsim::cli
