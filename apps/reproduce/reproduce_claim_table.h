// The paper's Sec. VI claims as data: one row per claim (its artefact, the
// paper's words and numbers, what is compared or the criterion, the verdict
// rule, our numbers), the table in apps/reproduce/reproduce_paper_claims.cpp.
// `uavsim reproduce` (apps/reproduce/reproduce_report.h) measures the
// artefacts into ClaimMeasurements and makes one ReproduceClaim per row, in
// the table's order, which is the order of claims.csv and of the report's
// verdicts. Adding a claim is adding a row (and, if it reads a quantity no
// artefact measures yet, measuring it).
//
// Texts name what they read in braces, expanded innermost first: {z0} (the
// scenario's latent size), {zlo} and {zhi} (the plan's smallest and
// largest), the variables of the comparison's range ({subset}, {z}, {more},
// {fewer}), and a measurement "{table/series/category[:decimals]}" ("table"
// is the artefact file's prefix, fig12 for fig12_alignment.csv, or fig11
// for what Figs. 11a and 11b give together), written as the mean over
// seeds with its 95 % interval ("6.14 ± 1.70"; a single number as it is,
// "" when not finite), to 2 decimals unless stated; a single number that is
// not zero gets the decimals its first significant digit needs (0.0002, not
// 0.000).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "apps/reproduce/reproduce_claims.h"

namespace uavsim::sim {

// What {…} in a comparison ranges over, in order.
enum class ClaimRange {
  kOnce,
  kEverySubset,      // {subset}: ModalitySubsets()
  kEveryLatentSize,  // {z}: the plan's latent sizes
  kSmallLatentSize,  // {z}: those at most 8 (the paper's "low-dimensional latent spaces")
  kSubsetPairs,      // {more} {fewer}: all over each pair, each pair over its two singles
};

// "{better} below {worse}" as the paper says it (apps/reproduce/reproduce_verdict.h):
// better and worse name per-seed measurements.
struct ComparisonPattern {
  enum Sense { kLowerBetter, kHigherBetter };  // higher (a rate, a gain): compared negated
  enum Split { kByTrajectory, kByFrame };      // by frame: judged into the frame-split verdict
  const char* what;                            // claims.csv's comparison
  const char* better;
  const char* worse;
  ClaimRange range = ClaimRange::kOnce;
  Sense sense = kLowerBetter;
  Split split = kByTrajectory;
};

// A claim judged by a criterion instead of comparisons over seeds; `values`
// name single numbers (kIntervalBelow: per-seed values).
struct ClaimCriterion {
  enum Kind {
    kNone,
    kSharesInRange,   // every value (a percentage of the original) in [lo, hi]: holds; every
                      // value below 100: mixed; else does not hold
    kFirstBelowRest,  // the first value below every other: holds, else does not hold
    kAtMost,          // the value at most hi: holds, else does not hold
    kRatioNearOne,    // |value - 1| below hi: holds, else does not hold
    kIntervalBelow,   // the 95 % interval of the values' mean below hi: holds; above hi:
                      // does not hold; else not resolved (one seed: the mean alone)
  };
  Kind kind = kNone;
  std::vector<const char*> values;
  double lo = 0.0, hi = 0.0;
  const char* detail = "";        // the verdict's detail
  const char* detail_mixed = "";  // instead when mixed (when not empty)
  const char* detail_fails = "";  // instead when it does not hold (when not empty)
};

// A number the paper reports, by the label its artefact gives it.
struct PaperValue {
  const char* label;
  double value;
};

struct ClaimRow {
  enum Rule {
    kAllHold,    // every comparison must hold (ClaimVerdict)
    kMostHold,   // "In most cases": more than half, none reversed; the words must begin so,
                 // since a redraw from claims.csv reads the rule from them (MostCasesClaim)
    kCriterion,  // `criterion` decides
  };
  const char* id;         // stable name of the claim: "fig12.te_align"
  const char* artefact;   // "Fig. 12" (claims.csv; the margin's table: ArtefactMargin)
  const char* statement;  // what the paper says, its numbers and ordering included
  Rule rule;
  std::vector<ComparisonPattern> comparisons;  // kAllHold, kMostHold: expanded in order
  ClaimCriterion criterion;                    // kCriterion
  const char* ours;                            // our numbers in a phrase (a text as above)
  const char* frame_note = "";                 // after the frame split's verdict (a text)
  std::vector<PaperValue> paper = {};          // the paper's numbers its artefact draws
  // The paper's value labelled `label`; throws std::logic_error when the row has none.
  double Paper(const std::string& label) const;
};

// The claims of Sec. VI (Figs. 7-15, Tables II-IV, one of Sec. VII), in the
// report's order.
const std::vector<ClaimRow>& PaperClaims();
// The row `id`; throws std::logic_error when there is none.
const ClaimRow& PaperClaim(const std::string& id);

// The paper's Table II, drawn beside ours: each modality's data rates in
// KB/s, original, pre-processed, then IB at each of `latent_dims`.
struct PaperDataRates {
  std::vector<int> latent_dims;
  std::map<std::string, std::vector<double>> kBps;
};
const PaperDataRates& PaperTable2();

// What the artefacts measured, for the claims to read.
struct ClaimMeasurements {
  std::map<std::string, std::vector<double>> seeds;  // per seed (index seed - 1), NaN: missing
  std::map<std::string, double> numbers;
  std::vector<int> latent_dims;  // the plan's, ascending
  int z0 = 0;                    // the scenario's latent size
  // "table/series/category".
  static std::string Key(const std::string& table, const std::string& series,
                         const std::string& category);
};

// The claim of a row from the measurements, not yet judged when it has
// comparisons (JudgeClaims), judged when it has a criterion. Throws
// std::logic_error naming the row for a measurement or variable that is
// not there, or a rule its words contradict.
ReproduceClaim MakeClaim(const ClaimRow& row, const ClaimMeasurements& measured);

}  // namespace uavsim::sim
