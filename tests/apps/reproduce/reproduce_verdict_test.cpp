// The four outcomes of a comparison, the claim rules and the seeds a
// comparison not resolved would need (issue 48), on constructed seed tables
// against hand computations from printed t tables.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "apps/reproduce/reproduce_verdict.h"

using uavsim::sim::ClaimVerdict;
using uavsim::sim::CompareSeeds;
using uavsim::sim::JudgeComparison;
using uavsim::sim::MostCasesClaim;
using uavsim::sim::Outcome;
using uavsim::sim::SdFromCi95;
using uavsim::sim::SeedStat;
using uavsim::sim::SeedsToExcludeZero;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Printed t tables: t_{0.975, 2}, t_{0.95, 2}.
constexpr double kT975_2 = 4.302652730;
constexpr double kT95_2 = 2.919985580;

Outcome Judge(const std::vector<double>& better, const std::vector<double>& worse, double margin) {
  return JudgeComparison(CompareSeeds("", better, worse).diff, margin).outcome;
}

}  // namespace

TEST_CASE("Reproduce verdicts: each of the four outcomes from a seed table", "[sim]") {
  const std::vector<double> zero = {0, 0, 0};
  // Differences 1.0, 1.1, 0.9: mean 1, sd 0.1, 95 % half-width 0.248 > 0.
  CHECK(Judge(zero, {1.0, 1.1, 0.9}, 0.5) == Outcome::kHolds);
  CHECK(Judge({1.0, 1.1, 0.9}, zero, 0.5) == Outcome::kReversed);
  // Differences 0.05, -0.05, 0: mean 0, sd 0.05; 95 % half-width 0.124
  // (straddles 0), 90 % half-width 2.920 * 0.05 / sqrt 3 = 0.0843 inside
  // +-0.5: no effect; inside +-0.08 it is not.
  const auto eq = JudgeComparison(CompareSeeds("", zero, {0.05, -0.05, 0.0}).diff, 0.5);
  CHECK(eq.outcome == Outcome::kNoEffect);
  CHECK(eq.ci90 == Approx(kT95_2 * 0.05 / std::sqrt(3.0)));
  CHECK(eq.seeds_needed == 0);
  CHECK(Judge(zero, {0.05, -0.05, 0.0}, 0.08) == Outcome::kNotResolved);
  // Differences -1, 1, 3: mean 1, sd 2; 95 % half-width 4.97, 90 % 3.37.
  const auto open = JudgeComparison(CompareSeeds("", zero, {-1, 1, 3}).diff, 0.5);
  CHECK(open.outcome == Outcome::kNotResolved);
  CHECK(open.seeds_needed == 18);  // by hand below
  // Beyond noise and inside the margin: by its sign.
  CHECK(Judge(zero, {0.10, 0.11, 0.09}, 0.5) == Outcome::kHolds);
  // No margin: nothing shows no effect.
  CHECK(Judge(zero, {0.05, -0.05, 0.0}, kNaN) == Outcome::kNotResolved);
  // One seed: the sign; none: not resolved.
  CHECK(Judge({1}, {3}, 0.5) == Outcome::kHolds);
  CHECK(Judge({3}, {1}, 0.5) == Outcome::kReversed);
  CHECK(Judge({kNaN}, {1}, 0.5) == Outcome::kNotResolved);
  CHECK(std::string(uavsim::sim::OutcomeName(Outcome::kNoEffect)) == "no effect");
  CHECK(std::string(uavsim::sim::OutcomeName(Outcome::kNotResolved)) == "not resolved");
}

TEST_CASE("Reproduce verdicts: the seeds to exclude 0, against a hand computation", "[sim]") {
  // Mean 1, sd 2: t_{0.975, n-1} * 2 / sqrt(n) < 1. From the t table:
  // n = 17: 2.1199 * 2 / 4.1231 = 1.0283 (no); n = 18: 2.1098 * 2 /
  // 4.2426 = 0.9946 (yes).
  CHECK(SeedsToExcludeZero(1.0, 2.0) == 18);
  CHECK(SeedsToExcludeZero(-1.0, 2.0) == 18);  // the sign does not matter
  // The city's camera IB below MLP at z 4 (claims.csv: -2.026150 +- 5.660110
  // over 3 seeds): sd = 5.660110 sqrt 3 / 4.3027 = 2.2785; n = 7: 2.4469 *
  // 2.2785 / 2.6458 = 2.107 (no), n = 8: 2.3646 * 2.2785 / 2.8284 = 1.905
  // (yes, below 2.026).
  const double sd = SdFromCi95(5.660110, 3);
  CHECK(sd == Approx(5.660110 * std::sqrt(3.0) / kT975_2));
  CHECK(SeedsToExcludeZero(-2.026150, sd) == 8);
  // Large: about (1.96 sd / mean)^2 = 38415 for mean 0.01, sd 1.
  const long long big = SeedsToExcludeZero(0.01, 1.0);
  CHECK(big >= 38415);
  CHECK(big <= 38420);
  CHECK(SeedsToExcludeZero(0.0, 1.0) == 0);
  CHECK(SeedsToExcludeZero(1.0, kNaN) == 0);
  CHECK(std::isnan(SdFromCi95(1.0, 1)));
  // From a half-width back to the statistics that gave it.
  SeedStat s;
  s.mean = 1.0, s.n = 3, s.sd = SdFromCi95(kT975_2 * 2.0 / std::sqrt(3.0), 3);
  CHECK(s.sd == Approx(2.0));
  CHECK(JudgeComparison(s, 0.5).seeds_needed == 18);
}

TEST_CASE("Reproduce verdicts: a claim from its comparisons", "[sim]") {
  const Outcome H = Outcome::kHolds, R = Outcome::kReversed, E = Outcome::kNoEffect,
                N = Outcome::kNotResolved;
  std::string detail;
  CHECK(ClaimVerdict({H, H}, false, &detail) == "holds");
  CHECK(detail == "2 of 2 comparisons hold");
  CHECK(ClaimVerdict({H, H, N}, true, nullptr) == "holds");  // "in most cases"
  CHECK(ClaimVerdict({H, N}, true, nullptr) == "mixed");     // not more than half
  CHECK(ClaimVerdict({H, H, R}, true, &detail) == "does not hold");
  CHECK(detail == "2 of 3 comparisons hold, 1 reversed");
  CHECK(ClaimVerdict({H, R}, false, nullptr) == "does not hold");
  CHECK(ClaimVerdict({E, E}, false, &detail) == "does not hold");
  CHECK(detail == "0 of 2 comparisons hold, 2 no effect");
  CHECK(ClaimVerdict({N, N, N}, false, &detail) == "not resolved");
  CHECK(detail == "0 of 3 comparisons hold, 3 not resolved");
  CHECK(ClaimVerdict({E, N}, false, &detail) == "not resolved");
  CHECK(detail == "0 of 2 comparisons hold, 1 no effect, 1 not resolved");
  CHECK(ClaimVerdict({H, E}, false, nullptr) == "mixed");
  CHECK(ClaimVerdict({H, N, N}, false, nullptr) == "mixed");
  CHECK(ClaimVerdict({}, false, nullptr) == "not measured");
  CHECK(MostCasesClaim("In most cases the best performance is with both MADW and MICA"));
  CHECK_FALSE(MostCasesClaim("UAVLoc outperforms all the considered baselines"));
}
