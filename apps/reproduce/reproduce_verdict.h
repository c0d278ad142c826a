// The statistics behind `uavsim reproduce`'s verdicts (apps/reproduce/reproduce.h),
// as pure functions: the same code judges a reproduction from its
// trainings' reports and redraws one from its claims.csv.
//
// A comparison "A below B" (the paper says A is better) is the per-seed
// difference B - A over the seeds where both are finite: its mean, standard
// deviation and count n. Against an equivalence margin m > 0 stated for the
// comparison's artefact it is
//   holds         the 95 % interval (Student t, two-sided) lies above 0
//   reversed      the 95 % interval lies below 0
//   no effect     the 90 % interval lies inside (-m, m): the two one-sided
//                 tests (TOST), each at the 5 % level
//   not resolved  none of these (and always when n = 0)
// in that order (a difference beyond noise and inside the margin counts by
// its sign). One seed (no spread): holds or reversed by the sign, else not
// resolved.
#pragma once

#include <limits>
#include <string>
#include <vector>

namespace uavsim::sim {

// The margin of every artefact whose comparisons are values of one kind
// (RMSE in m, rate in bit/s/Hz): this fraction of the mean, over the
// artefact's table, of the values it compares. Fixed in the plan record
// before any result exists (apps/reproduce/reproduce.h).
constexpr double kEquivalenceFraction = 0.10;

struct SeedStat {
  double mean = std::numeric_limits<double>::quiet_NaN();
  double sd = std::numeric_limits<double>::quiet_NaN();    // sample (n - 1); NaN for n < 2
  double ci95 = std::numeric_limits<double>::quiet_NaN();  // half-width; NaN for n < 2
  int n = 0;                                               // finite values
};
// Mean, sample standard deviation and Student-t 95 % half-width of the
// finite values (NaN: missing).
SeedStat SummariseSeeds(const std::vector<double>& values);

// The standard deviation behind a Student-t 95 % half-width over n >= 2
// values: ci95 sqrt(n) / t_{0.975, n-1} (NaN for n < 2).
double SdFromCi95(double ci95, int n);

struct SeedComparison {
  std::string what;
  SeedStat diff;  // worse - better per seed (where both are finite)
};
// "better below worse", seed by seed (index: seed - 1).
SeedComparison CompareSeeds(const std::string& what, const std::vector<double>& better,
                            const std::vector<double>& worse);

enum class Outcome { kHolds, kReversed, kNoEffect, kNotResolved };
// "holds", "reversed", "no effect", "not resolved".
const char* OutcomeName(Outcome o);

struct ComparisonVerdict {
  Outcome outcome = Outcome::kNotResolved;
  double ci90 = std::numeric_limits<double>::quiet_NaN();  // half-width; NaN for n < 2
  // Not resolved: SeedsToExcludeZero(mean, sd); 0 otherwise or when none.
  long long seeds_needed = 0;
};
// The rules above for a difference's statistics and margin (> 0; NaN or
// <= 0: no comparison can show no effect).
ComparisonVerdict JudgeComparison(const SeedStat& diff, double margin);

// The smallest n >= 2 with t_{0.975, n-1} sd / sqrt(n) < |mean|: the seeds
// at which this mean difference, with this spread, would exclude 0 at 95 %.
// 0 when there is none (mean 0, or mean or sd not finite).
long long SeedsToExcludeZero(double mean, double sd);

// A claim from its comparisons' outcomes: "holds" when all hold (most: more
// than half hold and none is reversed), "does not hold" when one is
// reversed or all show no effect, "not resolved" when none holds (the rest
// not resolved or no effect), else "mixed"; "not measured" without
// comparisons. `detail` (if not null) counts them: "1 of 3 comparisons
// hold, 1 no effect, 1 not resolved".
std::string ClaimVerdict(const std::vector<Outcome>& outcomes, bool most, std::string* detail);

// Whether the paper's words ask for most comparisons rather than all: the
// claim begins "In most cases".
bool MostCasesClaim(const std::string& paper);

}  // namespace uavsim::sim
