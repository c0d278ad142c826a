// The verdicts of a reproduction written into its folder (claims.csv,
// report.md, report.html): after its trainings (reproduce_report.cpp) or
// redrawn from the folder's own files (RedrawReproduceReport,
// reproduce_report.h). Judges, reads and writes files only: no LibTorch
// (apps/cli's light program links it).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "apps/reproduce/reproduce_claims.h"
#include "apps/reproduce/reproduce_document.h"

namespace uavsim::sim {

// Where the margin rule came from, when the plan record holds it.
inline constexpr const char* kRecordedRule =
    "written in the plan record (reproduce.json) before the first training";

// Judges the claims, puts the verdicts' rules (the margin's `provenance`
// in them) at the end of the protocol paragraph (block `protocol`,
// replacing those it carries), the verdicts at `summary_at` and every
// comparison at the end, and writes claims.csv, report.md and report.html
// into dir.
void WriteVerdicts(const std::string& dir, double fraction, const std::string& provenance,
                   std::vector<ReproduceClaim>& claims, ReportDocument& doc, std::size_t protocol,
                   std::size_t summary_at, const std::string& title);

}  // namespace uavsim::sim
