#include "apps/reproduce/reproduce_claims.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

#include "core/error.h"
#include "core/json_io.h"
#include "results/csv.h"

namespace uavsim::sim {
namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Fixed(double x, int decimals) {
  return std::isfinite(x) ? results::FormatFixed(x, decimals) : "";
}

// claims.csv has no quoting: commas in texts become ';'.
std::string Clean(std::string s) {
  std::replace(s.begin(), s.end(), ',', ';');
  return s;
}

// Rows of one artefact table whose `column` is (or, exclude, is not) `value`
// ("" column: every row), the values of `value_column`.
struct Source {
  const char* file;
  const char* value_column;
  const char* column;
  const char* value;
  bool exclude;
};

std::vector<Source> SourcesOf(const std::string& artefact, bool frame) {
  const char* split = frame ? "by frame" : "by trajectory";
  const Source f10a{"fig10a_modalities_preprocessed.csv", "rmse_m", "series", split, false};
  const Source f10b{"fig10b_modalities_raw.csv", "rmse_m", "", "", false};
  const Source f11a{"fig11a_temporal_preprocessed.csv", "rmse_m", "", "", false};
  const std::map<std::string, std::vector<Source>> sources = {
      {"Fig. 7", {{"fig07_camera_z.csv", "rmse_m", "", "", false}}},
      {"Fig. 8", {{"fig08_lidar_z.csv", "rmse_m", "", "", false}}},
      {"Fig. 9", {{"fig09_radar_z.csv", "rmse_m", "", "", false}}},
      {"Fig. 10a", {f10a}},
      {"Fig. 10b", {f10b}},
      {"Figs. 10a, 10b", {f10a, f10b}},
      {"Sec. VII", {f10a}},
      {"Table IV", {{"table4_camera_preprocessing.csv", "rmse_m", "", "", false}}},
      {"Fig. 11a", {f11a}},
      {"Fig. 11b", {f11a, {"fig11b_temporal_raw.csv", "rmse_m", "", "", false}}},
      {"Fig. 12", {{"fig12_alignment.csv", "rmse_m", "", "", false}}},
      {"Fig. 13", {{"fig13_fusion_modules.csv", "rmse_m", "", "", false}}},
      {"Fig. 14", {{"fig14_fusion_baselines.csv", "rmse_m", "", "", false}}},
      {"Fig. 15", {{"fig15_rate_snr.csv", "rate_bps_hz", "beam", "perfect", true}}}};
  std::string key = artefact;
  std::replace(key.begin(), key.end(), ';', ',');  // as claims.csv writes it
  const auto it = sources.find(key);
  return it == sources.end() ? std::vector<Source>{} : it->second;
}

std::string Unit(const std::string& artefact) { return artefact == "Fig. 15" ? "bit/s/Hz" : "m"; }

double Number(const std::string& cell, const std::string& where) {
  if (cell.empty()) return kNaN;
  try {
    std::size_t used = 0;
    const double x = std::stod(cell, &used);
    if (used == cell.size()) return x;
  } catch (const std::exception&) {
  }
  throw core::UsageError(where + ": expected a number, got '" + cell + "'");
}

// "8, 12, 40" or "5 to 2900 (median 41, 19 comparisons)"; "-" for none.
std::string SeedsCell(std::vector<long long> seeds) {
  if (seeds.empty()) return "-";
  std::sort(seeds.begin(), seeds.end());
  const auto one = [](long long s) { return s > 0 ? std::to_string(s) : std::string("none"); };
  std::string out;
  if (seeds.size() <= 3) {
    for (long long s : seeds) out += (out.empty() ? "" : ", ") + one(s);
    return out;
  }
  // Zeros (no count of seeds would do) sort first: they go last.
  std::rotate(seeds.begin(), std::upper_bound(seeds.begin(), seeds.end(), 0LL), seeds.end());
  return one(seeds.front()) + " to " + one(seeds.back()) + " (median " +
         one(seeds[(seeds.size() - 1) / 2]) + ", " + std::to_string(seeds.size()) + " comparisons)";
}

// The statistics as claims.csv keeps them (6 decimals, the spread from the
// half-width), so that a verdict judged from the trainings and one redrawn
// from claims.csv start from the same numbers.
SeedStat AsWritten(const SeedStat& d) {
  SeedStat w = d;
  if (std::isfinite(d.mean)) w.mean = std::stod(results::FormatFixed(d.mean, 6));
  if (std::isfinite(d.ci95)) w.ci95 = std::stod(results::FormatFixed(d.ci95, 6));
  w.sd = SdFromCi95(w.ci95, w.n);
  return w;
}

}  // namespace

const std::vector<std::string>& ModalitySubsets() {
  static const std::vector<std::string> s = {
      "all", "camera+lidar", "camera+radar", "lidar+radar", "camera", "lidar", "radar"};
  return s;
}

std::string MeanCiText(const SeedStat& s, int decimals) {
  if (s.n == 0) return "-";
  std::string t = results::FormatFixed(s.mean, decimals);
  if (std::isfinite(s.ci95)) t += " ± " + results::FormatFixed(s.ci95, decimals);
  return t;
}

double ArtefactMargin(const std::string& dir, const std::string& artefact, bool frame,
                      double fraction) {
  const std::vector<Source> sources = SourcesOf(artefact, frame);
  if (sources.empty()) return kNaN;
  double sum = 0.0;
  int n = 0;
  for (const Source& s : sources) {
    const std::string file = (fs::path(dir) / s.file).string();
    results::CsvFile csv;
    const std::string error = results::ReadCsvFile(file, &csv);
    if (!error.empty()) throw core::UsageError(file + ": " + error);
    const long value = csv.Column(s.value_column);
    const long column = *s.column ? csv.Column(s.column) : -2;
    if (value < 0 || column == -1)
      throw core::UsageError(file + ": expected columns " + s.value_column +
                             (*s.column ? std::string(" and ") + s.column : std::string()));
    for (std::size_t r = 0; r < csv.rows.size(); ++r) {
      const auto& row = csv.rows[r];
      if (column >= 0 && (row[static_cast<std::size_t>(column)] == s.value) == s.exclude) continue;
      const double x = Number(row[static_cast<std::size_t>(value)],
                              file + ": line " + std::to_string(csv.line[r]));
      if (std::isfinite(x)) sum += x, ++n;
    }
  }
  return n > 0 ? fraction * sum / n : kNaN;
}

void JudgeClaims(const std::string& dir, double fraction, std::vector<ReproduceClaim>& claims) {
  std::map<std::pair<std::string, bool>, double> margins;
  for (ReproduceClaim& c : claims) {
    if (c.comparisons.empty()) continue;
    std::vector<Outcome> split[2];
    for (ClaimComparison& cmp : c.comparisons) {
      const auto key = std::make_pair(c.artefact, cmp.frame);
      if (!margins.count(key)) margins[key] = ArtefactMargin(dir, c.artefact, cmp.frame, fraction);
      cmp.margin = margins[key];
      cmp.comparison.diff = AsWritten(cmp.comparison.diff);
      cmp.verdict = JudgeComparison(cmp.comparison.diff, cmp.margin);
      split[cmp.frame].push_back(cmp.verdict.outcome);
    }
    c.verdict = ClaimVerdict(split[0], c.most, &c.detail);
    if (!split[1].empty())
      c.frame_verdict = ClaimVerdict(split[1], c.most, nullptr) +
                        (c.frame_note.empty() ? "" : " " + c.frame_note);
  }
}

std::string ClaimsCsv(const std::vector<ReproduceClaim>& claims) {
  std::ostringstream csv;
  csv << "artefact,claim,ours,verdict,detail,frame_split_verdict,comparison,diff_mean,"
         "diff_ci95,seeds,comparison_verdict,split,diff_ci90,margin,seeds_needed\n";
  for (const ReproduceClaim& c : claims) {
    const std::string head = Clean(c.artefact) + "," + Clean(c.paper) + "," + Clean(c.ours) + "," +
                             c.verdict + "," + Clean(c.detail) + "," + Clean(c.frame_verdict) + ",";
    if (c.comparisons.empty()) csv << head << ",,,,,,,,\n";
    for (const ClaimComparison& cmp : c.comparisons) {
      const SeedStat& d = cmp.comparison.diff;
      const ComparisonVerdict& v = cmp.verdict;
      csv << head << Clean(cmp.comparison.what) << "," << Fixed(d.mean, 6) << ","
          << Fixed(d.ci95, 6) << "," << d.n << "," << OutcomeName(v.outcome) << ","
          << (cmp.frame ? "frame" : "trajectory") << "," << Fixed(v.ci90, 6) << ","
          << Fixed(cmp.margin, 6) << ","
          << (v.outcome == Outcome::kNotResolved ? std::to_string(v.seeds_needed) : "") << "\n";
    }
  }
  return csv.str();
}

std::vector<ReproduceClaim> ReadClaimsCsv(const std::string& file) {
  results::CsvFile csv;
  const std::string error = results::ReadCsvFile(file, &csv);
  if (!error.empty()) throw core::UsageError(file + ": " + error);
  std::map<std::string, long> col;
  for (const char* name : {"artefact", "claim", "ours", "verdict", "detail", "frame_split_verdict",
                           "comparison", "diff_mean", "diff_ci95", "seeds"}) {
    col[name] = csv.Column(name);
    if (col[name] < 0) throw core::UsageError(file + ": no column " + name);
  }
  const long split = csv.Column("split");
  std::vector<ReproduceClaim> claims;
  for (std::size_t r = 0; r < csv.rows.size(); ++r) {
    const auto& row = csv.rows[r];
    const auto at = [&](const char* name) { return row[static_cast<std::size_t>(col[name])]; };
    const std::string where = file + ": line " + std::to_string(csv.line[r]);
    if (claims.empty() || claims.back().artefact != at("artefact") ||
        claims.back().paper != at("claim")) {
      claims.push_back({});
      ReproduceClaim& c = claims.back();
      c.artefact = at("artefact"), c.paper = at("claim"), c.ours = at("ours");
      c.verdict = at("verdict"), c.detail = at("detail");
      c.frame_verdict = at("frame_split_verdict");
      c.most = MostCasesClaim(c.paper);
    }
    ReproduceClaim& c = claims.back();
    if (at("comparison").empty()) continue;  // a criterion's claim
    ClaimComparison cmp;
    cmp.comparison.what = at("comparison");
    SeedStat& d = cmp.comparison.diff;
    d.mean = Number(at("diff_mean"), where + ": diff_mean");
    d.ci95 = Number(at("diff_ci95"), where + ": diff_ci95");
    const double n = Number(at("seeds"), where + ": seeds");
    if (!(n >= 0 && n <= 1e6 && n == std::floor(n)))
      throw core::UsageError(where + ": seeds: expected a count, got '" + at("seeds") + "'");
    d.n = static_cast<int>(n);
    d.sd = SdFromCi95(d.ci95, d.n);
    cmp.frame = split >= 0 && row[static_cast<std::size_t>(split)] == "frame";
    c.comparisons.push_back(cmp);
  }
  for (ReproduceClaim& c : claims) {
    const bool frame = std::any_of(c.comparisons.begin(), c.comparisons.end(),
                                   [](const ClaimComparison& x) { return x.frame; });
    const std::size_t open = c.frame_verdict.find(" (");
    if (frame && open != std::string::npos) c.frame_note = c.frame_verdict.substr(open + 1);
  }
  return claims;
}

std::string VerdictRuleText(const std::vector<ReproduceClaim>& claims, double fraction,
                            const std::string& provenance) {
  std::string margins;
  std::map<std::pair<std::string, bool>, bool> seen;
  for (const ReproduceClaim& c : claims)
    for (const ClaimComparison& cmp : c.comparisons) {
      if (seen[{c.artefact, cmp.frame}] || !std::isfinite(cmp.margin)) continue;
      seen[{c.artefact, cmp.frame}] = true;
      margins += (margins.empty() ? "" : ", ") + c.artefact + (cmp.frame ? " by frame" : "") +
                 " ±" + results::FormatFixed(cmp.margin, 2) + " " + Unit(c.artefact);
    }
  return "Verdicts compare methods seed by seed on the same held-out flights: for each "
         "comparison the per-seed difference (positive on the paper's side), its mean and "
         "Student-t intervals over seeds. A comparison holds when its 95 % interval lies above "
         "0, is reversed when it lies below 0, shows no effect when its 90 % interval lies "
         "inside plus or minus the artefact's equivalence margin (the two one-sided tests, each "
         "at the 5 % level), and is otherwise not resolved; for each comparison not resolved "
         "the report gives the seeds at which its observed mean difference, with its observed "
         "spread, would exclude 0 at 95 % (`uavsim reproduce --seeds K` trains that many). The "
         "margin of an artefact is " +
         core::FormatNumber(100.0 * fraction) +
         " % of the mean, over its table, of the values it compares (held-out RMSE; Fig. 15: "
         "the rate of the estimated beams over the SNR grid), a rule " +
         provenance + ": " + (margins.empty() ? std::string("none here") : margins) +
         ". A claim holds when all its comparisons hold (\"in most cases\": more than half, "
         "none reversed), does not hold when one is reversed or all show no effect, is not "
         "resolved when none holds and none is reversed (the rest not resolved or no effect), "
         "else is mixed. Not resolved is not evidence against the paper.";
}

std::vector<ReportBlock> VerdictBlocks(const std::vector<ReproduceClaim>& claims) {
  std::map<std::string, int> count;
  std::vector<std::vector<std::string>> rows{{"artefact", "the paper says",
                                              "uavsim (mean ± 95 % CI)", "verdict",
                                              "seeds to resolve", "frame split"}};
  for (const ReproduceClaim& c : claims) {
    ++count[c.verdict];
    std::vector<long long> seeds;
    for (const ClaimComparison& cmp : c.comparisons)
      if (!cmp.frame && cmp.verdict.outcome == Outcome::kNotResolved)
        seeds.push_back(cmp.verdict.seeds_needed);
    rows.push_back({c.artefact, c.paper, c.ours,
                    c.verdict + (c.detail.empty() ? "" : ": " + c.detail), SeedsCell(seeds),
                    c.frame_verdict.empty() ? "-" : c.frame_verdict});
  }
  const std::string text =
      std::to_string(claims.size()) + " claims: " + std::to_string(count["holds"]) + " hold, " +
      std::to_string(count["does not hold"]) + " do not hold, " +
      std::to_string(count["not resolved"]) + " not resolved, " + std::to_string(count["mixed"]) +
      " mixed. \"Seeds to resolve\": for the comparisons not resolved, the seeds at which each "
      "would exclude 0 (its observed mean and spread held fixed: a rough figure, the spread of "
      "a few seeds is itself uncertain). Every comparison is in the last section and in "
      "claims.csv.";
  return {{ReportBlock::kHeading, "Verdicts", "", {}},
          {ReportBlock::kText, text, "", {}},
          {ReportBlock::kTable, "", "", rows}};
}

std::vector<ReportBlock> ComparisonBlocks(const std::vector<ReproduceClaim>& claims) {
  std::vector<std::vector<std::string>> rows{{"artefact", "comparison",
                                              "difference (mean ± 95 % CI)", "90 % CI", "margin",
                                              "seeds", "verdict", "seeds to resolve"}};
  for (const ReproduceClaim& c : claims)
    for (const ClaimComparison& cmp : c.comparisons) {
      const SeedStat& d = cmp.comparison.diff;
      const ComparisonVerdict& v = cmp.verdict;
      std::string diff = d.n == 0 ? "-" : results::FormatFixed(d.mean, 2);
      if (std::isfinite(d.ci95)) diff += " ± " + results::FormatFixed(d.ci95, 2);
      rows.push_back({c.artefact + (cmp.frame ? " (by frame)" : ""), cmp.comparison.what, diff,
                      std::isfinite(v.ci90) ? "± " + results::FormatFixed(v.ci90, 2) : "-",
                      std::isfinite(cmp.margin) ? "± " + results::FormatFixed(cmp.margin, 2) : "-",
                      std::to_string(d.n), OutcomeName(v.outcome),
                      v.outcome == Outcome::kNotResolved ? SeedsCell({v.seeds_needed}) : "-"});
    }
  return {{ReportBlock::kHeading, "Every comparison", "", {}},
          {ReportBlock::kText,
           "Each comparison of the verdicts above (as in claims.csv): the mean per-seed "
           "difference, positive on the paper's side (m; Fig. 15 bit/s/Hz), with its 95 % "
           "interval; the 90 % interval of the no-effect test; the artefact's margin; the "
           "seeds; the verdict; when not resolved, the seeds at which the observed mean and "
           "spread would exclude 0 at 95 % (Student t).",
           "",
           {}},
          {ReportBlock::kTable, "", "", rows}};
}

}  // namespace uavsim::sim
