#include "apps/reproduce/reproduce_verdict.h"

#include <algorithm>
#include <cmath>

#include "results/sweep_report.h"  // StudentT975, StudentTQuantile

namespace uavsim::sim {

SeedStat SummariseSeeds(const std::vector<double>& v) {
  SeedStat s;
  double sum = 0.0;
  for (double x : v)
    if (std::isfinite(x)) sum += x, ++s.n;
  if (s.n == 0) return s;
  s.mean = sum / s.n;
  if (s.n < 2) return s;
  double ss = 0.0;
  for (double x : v)
    if (std::isfinite(x)) ss += (x - s.mean) * (x - s.mean);
  s.sd = std::sqrt(ss / (s.n - 1));
  s.ci95 = results::StudentT975(s.n - 1) * s.sd / std::sqrt(s.n);
  return s;
}

double SdFromCi95(double ci95, int n) {
  if (n < 2 || !std::isfinite(ci95)) return std::numeric_limits<double>::quiet_NaN();
  return ci95 * std::sqrt(static_cast<double>(n)) / results::StudentT975(n - 1);
}

SeedComparison CompareSeeds(const std::string& what, const std::vector<double>& better,
                            const std::vector<double>& worse) {
  std::vector<double> d;
  for (std::size_t i = 0; i < better.size() && i < worse.size(); ++i)
    if (std::isfinite(better[i]) && std::isfinite(worse[i])) d.push_back(worse[i] - better[i]);
  return {what, SummariseSeeds(d)};
}

const char* OutcomeName(Outcome o) {
  switch (o) {
    case Outcome::kHolds:
      return "holds";
    case Outcome::kReversed:
      return "reversed";
    case Outcome::kNoEffect:
      return "no effect";
    case Outcome::kNotResolved:
      break;
  }
  return "not resolved";
}

ComparisonVerdict JudgeComparison(const SeedStat& d, double margin) {
  ComparisonVerdict v;
  if (d.n == 0 || !std::isfinite(d.mean)) return v;
  if (d.n < 2 || !std::isfinite(d.sd)) {
    // One seed: no spread, no interval; the sign alone.
    v.outcome = d.mean > 0 ? Outcome::kHolds : d.mean < 0 ? Outcome::kReversed : v.outcome;
    return v;
  }
  const double se = d.sd / std::sqrt(static_cast<double>(d.n));
  const double ci95 = results::StudentT975(d.n - 1) * se;
  v.ci90 = results::StudentTQuantile(d.n - 1, 0.95) * se;
  if (d.mean - ci95 > 0) {
    v.outcome = Outcome::kHolds;
  } else if (d.mean + ci95 < 0) {
    v.outcome = Outcome::kReversed;
  } else if (margin > 0 && d.mean - v.ci90 > -margin && d.mean + v.ci90 < margin) {
    v.outcome = Outcome::kNoEffect;
  } else {
    v.seeds_needed = SeedsToExcludeZero(d.mean, d.sd);
  }
  return v;
}

long long SeedsToExcludeZero(double mean, double sd) {
  if (!std::isfinite(mean) || !std::isfinite(sd) || mean == 0.0) return 0;
  const double m = std::abs(mean);
  // t_{0.975, n-1} exceeds the normal quantile z for every n, so no n below
  // (z sd / m)^2 can do; from there t falls towards z within a few steps.
  const double z = 1.959963984540054;
  const double lower = std::floor(std::pow(z * sd / m, 2));
  if (lower > 1e15) return 0;  // beyond any count of seeds worth printing
  long long n = std::max(2LL, static_cast<long long>(lower));
  const auto excludes = [&](long long k) {
    const double t = k - 1 > 1000000 ? z : results::StudentT975(static_cast<int>(k - 1));
    return t * sd / std::sqrt(static_cast<double>(k)) < m;
  };
  while (!excludes(n)) ++n;
  return n;
}

std::string ClaimVerdict(const std::vector<Outcome>& outcomes, bool most, std::string* detail) {
  int hold = 0, reversed = 0, none = 0, open = 0;
  for (Outcome o : outcomes) {
    hold += o == Outcome::kHolds;
    reversed += o == Outcome::kReversed;
    none += o == Outcome::kNoEffect;
    open += o == Outcome::kNotResolved;
  }
  const int n = static_cast<int>(outcomes.size());
  if (detail) {
    *detail = std::to_string(hold) + " of " + std::to_string(n) + " comparisons hold";
    if (reversed) *detail += ", " + std::to_string(reversed) + " reversed";
    if (none) *detail += ", " + std::to_string(none) + " no effect";
    if (open) *detail += ", " + std::to_string(open) + " not resolved";
  }
  if (n == 0) return "not measured";
  if (most ? (2 * hold > n && reversed == 0) : hold == n) return "holds";
  if (reversed > 0 || none == n) return "does not hold";
  if (hold == 0) return "not resolved";
  return "mixed";
}

bool MostCasesClaim(const std::string& paper) { return paper.rfind("In most cases", 0) == 0; }

}  // namespace uavsim::sim
