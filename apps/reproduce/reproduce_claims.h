// The claims of a `uavsim reproduce` report (apps/reproduce/reproduce_report.h):
// judged by the rules of apps/reproduce/reproduce_verdict.h, written to claims.csv and
// into the report's verdict sections, and read back from claims.csv, so
// that a reproduction's verdicts can be redrawn from its committed tables
// alone (`uavsim report DIR`) by the same code that judged them.
#pragma once

#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "apps/reproduce/reproduce_document.h"
#include "apps/reproduce/reproduce_verdict.h"

namespace uavsim::sim {

struct ClaimComparison {
  ClaimComparison() = default;
  ClaimComparison(SeedComparison c, bool frame_split = false)  // NOLINT: implicit on purpose
      : comparison(std::move(c)), frame(frame_split) {}
  SeedComparison comparison;
  bool frame = false;  // Fig. 10a's split by frame (judged into frame_verdict)
  double margin = std::numeric_limits<double>::quiet_NaN();  // set by JudgeClaims
  ComparisonVerdict verdict;                                 // set by JudgeClaims
};

struct ReproduceClaim {
  std::string artefact;  // "Fig. 12"
  std::string paper;     // what the paper says
  std::string ours;      // our numbers in a phrase
  // "In most cases": more than half of the comparisons must hold, none
  // reversed (ClaimVerdict); else all must.
  bool most = false;
  // Empty: judged by a criterion, whose verdict and detail are set directly.
  std::vector<ClaimComparison> comparisons;
  std::string verdict, detail;  // holds / does not hold / not resolved / mixed
  std::string frame_verdict;    // Fig. 10a's frame split ("" when not measured)
  std::string frame_note;       // what follows it: "(all 4.71 ± 1.63 m)"
};

// The modality subsets in the order of the paper's figures: "all",
// "camera+lidar", "camera+radar", "lidar+radar", "camera", "lidar", "radar".
const std::vector<std::string>& ModalitySubsets();

// "6.82 ± 0.41": the mean and 95 % half-width to `decimals` ("6.82" for
// one seed, "-" for none).
std::string MeanCiText(const SeedStat& s, int decimals = 2);

// The equivalence margin of an artefact: `fraction` times the mean of the
// values its claims compare, over the artefact's table in DIR (the RMSE
// CSVs of Figs. 7-14 and Tab. IV, Fig. 10a's split by trajectory or by
// frame, Fig. 11b with 11a, Figs. 10a/10b together; Fig. 15 the rates of
// every beam but the perfect one). NaN for an artefact without such a
// table. Throws core::UsageError when a table is missing or malformed.
double ArtefactMargin(const std::string& dir, const std::string& artefact, bool frame,
                      double fraction);

// Every comparison's margin and verdict, then every claim's verdict and
// detail from its comparisons by its rule (`most`), the frame split's into
// frame_verdict; claims without comparisons are left as they are. Each
// difference is first rounded as claims.csv writes it (mean and half-width
// to 6 decimals, the sd from the half-width), so that judging from the
// trainings and redrawing from claims.csv give the same bytes.
void JudgeClaims(const std::string& dir, double fraction, std::vector<ReproduceClaim>& claims);

// claims.csv: a row per comparison (a criterion's claim: one row without),
// commas in texts written as ';'. Columns: artefact, claim, ours, verdict,
// detail, frame_split_verdict, comparison, diff_mean, diff_ci95, seeds,
// comparison_verdict, split (trajectory / frame), diff_ci90, margin,
// seeds_needed (not resolved only; 0 when no count of seeds would do).
std::string ClaimsCsv(const std::vector<ReproduceClaim>& claims);
// The claims of a claims.csv (written by ClaimsCsv or by the three-outcome
// reports before it, which lack the last four columns), with each
// comparison's statistics (sd from the half-width), not yet judged; the
// rule (`most`) from the claim's words (MostCasesClaim), as claims.csv has
// no column for it.
// Throws core::UsageError naming the file and line.
std::vector<ReproduceClaim> ReadClaimsCsv(const std::string& file);

// The protocol's sentences on the verdicts: the rules, the margin rule
// ("a rule <provenance>: ") and each artefact's margin.
std::string VerdictRuleText(const std::vector<ReproduceClaim>& claims, double fraction,
                            const std::string& provenance);
// "## Verdicts": the counts and a row per claim; "## Every comparison": a
// row per comparison with its intervals, margin, verdict and seeds needed.
std::vector<ReportBlock> VerdictBlocks(const std::vector<ReproduceClaim>& claims);
std::vector<ReportBlock> ComparisonBlocks(const std::vector<ReproduceClaim>& claims);

}  // namespace uavsim::sim
