#include "apps/reproduce/reproduce_claim_table.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "results/csv.h"

namespace uavsim::sim {
namespace {

using Vars = std::map<std::string, std::string>;
using Seeds = std::vector<double>;

// The bindings of a comparison's range, in order.
std::vector<Vars> Bindings(ClaimRange range, const ClaimMeasurements& m) {
  std::vector<Vars> out;
  switch (range) {
    case ClaimRange::kOnce:
      out.push_back({});
      break;
    case ClaimRange::kEverySubset:
      for (const std::string& s : ModalitySubsets()) out.push_back({{"subset", s}});
      break;
    case ClaimRange::kEveryLatentSize:
    case ClaimRange::kSmallLatentSize:
      for (int z : m.latent_dims)
        if (range == ClaimRange::kEveryLatentSize || z <= 8)
          out.push_back({{"z", std::to_string(z)}});
      break;
    case ClaimRange::kSubsetPairs:
      for (const auto& [more, fewer] :
           std::vector<std::pair<const char*, const char*>>{{"all", "camera+lidar"},
                                                            {"all", "camera+radar"},
                                                            {"all", "lidar+radar"},
                                                            {"camera+lidar", "camera"},
                                                            {"camera+lidar", "lidar"},
                                                            {"camera+radar", "camera"},
                                                            {"camera+radar", "radar"},
                                                            {"lidar+radar", "lidar"},
                                                            {"lidar+radar", "radar"}})
        out.push_back({{"more", more}, {"fewer", fewer}});
      break;
  }
  return out;
}

// Reads the measurements for one row, naming it in what it throws.
class Reader {
 public:
  Reader(const ClaimRow& row, const ClaimMeasurements& m) : row_(row), m_(m) {
    vars_ = {{"z0", std::to_string(m.z0)}};
    if (!m.latent_dims.empty()) {
      vars_["zlo"] = std::to_string(m.latent_dims.front());
      vars_["zhi"] = std::to_string(m.latent_dims.back());
    }
  }

  // `text` with every {…} expanded, innermost first (the header's rules),
  // with `extra` variables beside the row's.
  std::string Expand(std::string text, const Vars& extra = {}) const {
    for (std::size_t close = text.find('}'); close != std::string::npos; close = text.find('}')) {
      const std::size_t open = text.rfind('{', close);
      if (open == std::string::npos) Fail("unmatched '}' in \"" + text + "\"");
      const std::string name = text.substr(open + 1, close - open - 1);
      text.replace(open, close - open + 1,
                   name.find('/') != std::string::npos ? Measured(name) : Variable(name, extra));
    }
    if (text.find('{') != std::string::npos) Fail("unmatched '{' in \"" + text + "\"");
    return text;
  }

  const Seeds& PerSeed(const std::string& key) const {
    const auto it = m_.seeds.find(key);
    if (it == m_.seeds.end()) Fail("nothing measured per seed as \"" + key + "\"");
    return it->second;
  }
  double Number(const std::string& key) const {
    const auto it = m_.numbers.find(key);
    if (it == m_.numbers.end()) Fail("no number measured as \"" + key + "\"");
    return it->second;
  }
  [[noreturn]] void Fail(const std::string& what) const {
    throw std::logic_error(std::string("claim ") + row_.id + ": " + what);
  }

 private:
  std::string Variable(const std::string& name, const Vars& extra) const {
    auto it = extra.find(name);
    if (it != extra.end()) return it->second;
    it = vars_.find(name);
    if (it == vars_.end()) Fail("no variable {" + name + "}");
    return it->second;
  }
  // "table/series/category[:decimals]", as the header says.
  std::string Measured(const std::string& name) const {
    std::string key = name;
    int decimals = 2;
    const std::size_t colon = name.rfind(':');
    if (colon != std::string::npos) {
      key = name.substr(0, colon);
      decimals = std::stoi(name.substr(colon + 1));
    }
    if (m_.seeds.count(key)) return MeanCiText(SummariseSeeds(m_.seeds.at(key)), decimals);
    const double x = Number(key);
    if (!std::isfinite(x)) return "";
    while (x != 0.0 && decimals < 12 && std::abs(x) < 0.5 * std::pow(10.0, -decimals)) ++decimals;
    return results::FormatFixed(x, decimals);
  }

  const ClaimRow& row_;
  const ClaimMeasurements& m_;
  Vars vars_;
};

void AddComparisons(const ClaimRow& row, const Reader& read, const ClaimMeasurements& m,
                    ReproduceClaim& c) {
  for (const ComparisonPattern& p : row.comparisons)
    for (const Vars& vars : Bindings(p.range, m)) {
      Seeds better = read.PerSeed(read.Expand(p.better, vars));
      Seeds worse = read.PerSeed(read.Expand(p.worse, vars));
      if (p.sense == ComparisonPattern::kHigherBetter) {
        // CompareSeeds reads "better below worse".
        for (double& x : better) x = -x;
        for (double& x : worse) x = -x;
      }
      c.comparisons.push_back(
          ClaimComparison(CompareSeeds(read.Expand(p.what, vars), better, worse),
                          p.split == ComparisonPattern::kByFrame));
    }
}

// The criterion's verdict: "holds", "mixed", "does not hold" or "not resolved".
std::string CriterionVerdict(const ClaimCriterion& k, const Reader& read) {
  std::vector<double> x;
  if (k.kind != ClaimCriterion::kIntervalBelow)
    for (const char* v : k.values) x.push_back(read.Number(v));
  if (k.kind != ClaimCriterion::kNone && k.values.empty()) read.Fail("a criterion of no value");
  const auto all = [&](auto test) { return std::all_of(x.begin(), x.end(), test); };
  switch (k.kind) {
    case ClaimCriterion::kSharesInRange: {
      const bool in = all([&](double v) { return v >= k.lo && v <= k.hi; });
      const bool below = all([](double v) { return v < 100; });
      return in ? "holds" : below ? "mixed" : "does not hold";
    }
    case ClaimCriterion::kFirstBelowRest:
      return std::all_of(x.begin() + 1, x.end(), [&](double v) { return x[0] < v; })
                 ? "holds"
                 : "does not hold";
    case ClaimCriterion::kAtMost:
      return x[0] <= k.hi ? "holds" : "does not hold";
    case ClaimCriterion::kRatioNearOne:
      return std::abs(x[0] - 1.0) < k.hi ? "holds" : "does not hold";
    case ClaimCriterion::kIntervalBelow: {
      const SeedStat g = SummariseSeeds(read.PerSeed(k.values[0]));
      const double upper = std::isfinite(g.ci95) ? g.mean + g.ci95 : g.mean;
      const double lower = std::isfinite(g.ci95) ? g.mean - g.ci95 : g.mean;
      return upper < k.hi ? "holds" : lower > k.hi ? "does not hold" : "not resolved";
    }
    case ClaimCriterion::kNone:
      break;
  }
  read.Fail("a criterion rule without a criterion");
}

}  // namespace

double ClaimRow::Paper(const std::string& label) const {
  for (const PaperValue& p : paper)
    if (label == p.label) return p.value;
  throw std::logic_error(std::string("claim ") + id + ": no paper value '" + label + "'");
}

const ClaimRow& PaperClaim(const std::string& id) {
  for (const ClaimRow& row : PaperClaims())
    if (id == row.id) return row;
  throw std::logic_error("no claim '" + id + "' in the table of the paper's claims");
}

std::string ClaimMeasurements::Key(const std::string& table, const std::string& series,
                                   const std::string& category) {
  return table + "/" + series + "/" + category;
}

ReproduceClaim MakeClaim(const ClaimRow& row, const ClaimMeasurements& measured) {
  const Reader read(row, measured);
  ReproduceClaim c;
  c.artefact = row.artefact;
  c.paper = row.statement;
  c.most = row.rule == ClaimRow::kMostHold;
  if (c.most != MostCasesClaim(c.paper))
    read.Fail("its rule and its words disagree on \"In most cases\"");
  c.ours = read.Expand(row.ours);
  c.frame_note = read.Expand(row.frame_note);
  if (row.rule == ClaimRow::kCriterion) {
    const ClaimCriterion& k = row.criterion;
    c.verdict = CriterionVerdict(k, read);
    c.detail = c.verdict == "mixed" && *k.detail_mixed           ? k.detail_mixed
               : c.verdict == "does not hold" && *k.detail_fails ? k.detail_fails
                                                                 : k.detail;
  } else {
    AddComparisons(row, read, measured, c);
  }
  return c;
}

}  // namespace uavsim::sim
