// A sweep's report: the points' metrics gathered into one table (a column per
// metric), grouped into settings with mean and 95 % confidence interval, and
// drawn as curves. Everything is built and checked in memory first; files are
// written only once the inputs are known to be consistent.
#include "results/sweep_report.h"

#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "results/csv.h"
#include "results/gnuplot.h"
#include "results/html.h"
#include "results/panel_plot.h"
#include "results/plot.h"
#include "results/run_directory.h"

namespace uavsim::results {
namespace {

namespace fs = std::filesystem;
using Value = std::optional<double>;

// ---------------------------------------------------------------------------
// Cells and numbers

// A text as a plain CSV cell: ',' -> ';' (no cell splits), '"' -> '\''
// (no reader takes it for quoting), control characters -> ' ' (no row
// splits).
std::string CleanCell(const std::string& s) {
  std::string out = s;
  for (char& c : out) {
    if (c == ',')
      c = ';';
    else if (c == '"')
      c = '\'';
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      c = ' ';
  }
  return out;
}

// A value as summary/aggregate cells show it: 6 decimals, "" when missing.
std::string Cell(const Value& v) { return v ? FormatFixed(*v, 6) : std::string(); }

// An SNR cell as a column name shows it: trailing zeros (and a bare point)
// trimmed, "-10.00" -> "-10", "2.50" -> "2.5", "-0.00" -> "0".
std::string TrimSnr(std::string s) {
  if (s.find('.') != std::string::npos && s.find_first_of("eE") == std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

// "<title>: <what>", or just <what> for an untitled sweep.
std::string Titled(const std::string& title, const std::string& what) {
  return title.empty() ? what : title + ": " + what;
}

// ---------------------------------------------------------------------------
// One point's rate_snr.csv

struct PointRates {
  std::vector<std::string> beams;                         // in order of appearance
  std::map<double, std::string> snr_text;                 // SNR -> trimmed text
  std::map<std::pair<std::string, double>, double> rate;  // (beam, SNR) -> rate
};

// Parses "snr_db,beam,rate_bps_hz" rows (columns found by name). Empty text =
// no rates. Throws std::invalid_argument naming the point for anything else
// malformed.
PointRates ParseRateSnr(const SweepPoint& point) {
  PointRates out;
  const auto fail = [&](const std::string& what) {
    return std::invalid_argument("sweep report: point " + point.id + ": rate_snr.csv " + what);
  };
  std::vector<std::string> header;
  long snr_c = -1, beam_c = -1, rate_c = -1;
  std::size_t line_no = 0, start = 0;
  const std::string& text = point.rate_snr_csv;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    start = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    std::vector<std::string> cells = SplitCsvLine(line);
    if (header.empty()) {
      header = std::move(cells);
      for (std::size_t i = 0; i < header.size(); ++i) {
        if (header[i] == "snr_db") snr_c = static_cast<long>(i);
        if (header[i] == "beam") beam_c = static_cast<long>(i);
        if (header[i] == "rate_bps_hz") rate_c = static_cast<long>(i);
      }
      if (snr_c < 0 || beam_c < 0 || rate_c < 0)
        throw fail("lacks the columns snr_db, beam and rate_bps_hz");
      continue;
    }
    const std::string at = "line " + std::to_string(line_no) + ": ";
    if (cells.size() != header.size()) throw fail(at + "wrong number of cells");
    double snr = 0.0, rate = 0.0;
    if (!ParseFiniteNumber(cells[snr_c], &snr) || !ParseFiniteNumber(cells[rate_c], &rate))
      throw fail(at + "expected finite numbers in snr_db and rate_bps_hz");
    if (snr == 0.0) snr = 0.0;  // -0 and 0 are one SNR
    const std::string& beam = cells[beam_c];
    if (beam.empty()) throw fail(at + "empty beam name");
    bool known = false;
    for (const auto& b : out.beams) known = known || b == beam;
    if (!known) out.beams.push_back(beam);
    out.snr_text.emplace(snr, TrimSnr(cells[snr_c]));
    out.rate[{beam, snr}] = rate;
  }
  return out;
}

// ---------------------------------------------------------------------------
// The metric columns and each point's values

enum class Kind { kRmse, kCoverage, kDelivery, kGospa, kRate };

struct Metric {
  std::string name;  // summary.csv column
  Kind kind;
  std::string key;      // method, modality or beam
  double snr_db = 0.0;  // kRate
  std::string snr_text;
};

// rmse_m.<method>: a finite number, else missing (null: never estimated).
Value RmseOf(const core::Json& metrics, const std::string& method) {
  if (!metrics.contains("rmse_m") || !metrics["rmse_m"].contains(method)) return std::nullopt;
  const core::Json& v = metrics["rmse_m"][method];
  if (!v.is_number()) return std::nullopt;
  const double x = v.get<double>();
  return std::isfinite(x) ? Value(x) : std::nullopt;
}

// estimated_windows.<method> / windows: the share of windows the method had
// an estimate for (its RMSE covers only those); missing when absent.
Value CoverageOf(const core::Json& metrics, const std::string& method) {
  if (!metrics.contains("windows") || !metrics.contains("estimated_windows") ||
      !metrics["estimated_windows"].contains(method))
    return std::nullopt;
  const core::Json &n = metrics["windows"], &k = metrics["estimated_windows"][method];
  if (!n.is_number() || !k.is_number() || !(n.get<double>() > 0.0)) return std::nullopt;
  return k.get<double>() / n.get<double>();
}

// modalities.<modality>: packets_delivered / packets_sent; missing when
// nothing was sent or the counts are absent.
Value DeliveryOf(const core::Json& metrics, const std::string& modality) {
  if (!metrics.contains("modalities") || !metrics["modalities"].contains(modality))
    return std::nullopt;
  const core::Json& m = metrics["modalities"][modality];
  if (!m.contains("packets_sent") || !m.contains("packets_delivered")) return std::nullopt;
  const core::Json &sent = m["packets_sent"], &delivered = m["packets_delivered"];
  if (!sent.is_number() || !delivered.is_number() || !(sent.get<double>() > 0.0))
    return std::nullopt;
  return delivered.get<double>() / sent.get<double>();
}

// gospa.methods.<method>.rms_m (several targets, or a multi-target method).
Value GospaOf(const core::Json& metrics, const std::string& method) {
  const core::Json::json_pointer p("/gospa/methods/" + method + "/rms_m");
  if (!metrics.contains(p) || !metrics[p].is_number()) return std::nullopt;
  return metrics[p].get<double>();
}

// The keys of the object at metrics' pointer `field` over all points, sorted.
std::set<std::string> KeysOver(const std::vector<SweepPoint>& points, const char* field) {
  std::set<std::string> keys;
  const core::Json::json_pointer at(std::string("/") + field);
  for (const auto& p : points)
    if (p.metrics.contains(at) && p.metrics[at].is_object())
      for (auto it = p.metrics[at].begin(); it != p.metrics[at].end(); ++it) keys.insert(it.key());
  return keys;
}

// The metric columns, in summary.csv order: rmse_*, coverage_* and
// delivery_* sorted by name, then rate_<beam>_<snr>dB for beams in first-seen order x SNR
// ascending.
std::vector<Metric> CollectMetrics(const SweepReportInputs& in,
                                   const std::vector<PointRates>& rates) {
  std::vector<Metric> metrics;
  for (const auto& method : KeysOver(in.points, "rmse_m"))
    metrics.push_back({"rmse_" + CleanCell(method), Kind::kRmse, method, 0.0, ""});
  for (const auto& method : KeysOver(in.points, "estimated_windows"))
    metrics.push_back({"coverage_" + CleanCell(method), Kind::kCoverage, method, 0.0, ""});
  for (const auto& modality : KeysOver(in.points, "modalities"))
    metrics.push_back({"delivery_" + CleanCell(modality), Kind::kDelivery, modality, 0.0, ""});
  for (const auto& method : KeysOver(in.points, "gospa/methods"))
    metrics.push_back({"gospa_" + CleanCell(method), Kind::kGospa, method, 0.0, ""});
  std::vector<std::string> beams;
  std::map<double, std::string> snrs;
  for (const auto& r : rates) {
    for (const auto& b : r.beams) {
      bool known = false;
      for (const auto& seen : beams) known = known || seen == b;
      if (!known) beams.push_back(b);
    }
    snrs.insert(r.snr_text.begin(), r.snr_text.end());
  }
  for (const auto& beam : beams)
    for (const auto& [snr, text] : snrs)
      metrics.push_back(
          {"rate_" + CleanCell(beam) + "_" + text + "dB", Kind::kRate, beam, snr, text});
  return metrics;
}

// One point's value of one metric.
Value ValueOf(const SweepPoint& point, const PointRates& rates, const Metric& m) {
  switch (m.kind) {
    case Kind::kRmse:
      return RmseOf(point.metrics, m.key);
    case Kind::kCoverage:
      return CoverageOf(point.metrics, m.key);
    case Kind::kDelivery:
      return DeliveryOf(point.metrics, m.key);
    case Kind::kGospa:
      return GospaOf(point.metrics, m.key);
    case Kind::kRate: {
      const auto it = rates.rate.find({m.key, m.snr_db});
      return it == rates.rate.end() ? std::nullopt : Value(it->second);
    }
  }
  return std::nullopt;
}

// ---------------------------------------------------------------------------
// Settings and their statistics

struct Stats {
  Value mean;  // over the points having a value
  Value ci95;  // half-width; needs two values
};

Stats Summarise(const std::vector<double>& xs) {
  Stats s;
  const std::size_t n = xs.size();
  if (n == 0) return s;
  double sum = 0.0;
  for (double x : xs) sum += x;
  const double mean = sum / static_cast<double>(n);
  s.mean = mean;
  if (n < 2) return s;
  double squares = 0.0;
  for (double x : xs) squares += (x - mean) * (x - mean);
  const double sd = std::sqrt(squares / static_cast<double>(n - 1));
  s.ci95 = StudentT975(static_cast<int>(n - 1)) * sd / std::sqrt(static_cast<double>(n));
  return s;
}

struct Setting {
  std::vector<int> value_index;
  std::vector<std::size_t> points;  // indices into in.points
  std::vector<Stats> stats;         // per metric
};

// Everything the files are written from.
struct Report {
  const SweepReportInputs& in;
  std::vector<Metric> metrics;
  std::vector<std::vector<Value>> values;  // [point][metric]
  std::vector<Setting> settings;           // in order of first appearance
  std::map<std::vector<int>, std::size_t> setting_of;
  std::vector<bool> varies;  // per parameter: more than one value among the points
};

// Groups the points into settings and summarises each metric over them.
void GroupSettings(Report& r) {
  for (std::size_t i = 0; i < r.in.points.size(); ++i) {
    const auto& vi = r.in.points[i].value_index;
    const auto [it, added] = r.setting_of.emplace(vi, r.settings.size());
    if (added) r.settings.push_back({vi, {}, {}});
    r.settings[it->second].points.push_back(i);
  }
  for (auto& s : r.settings)
    for (std::size_t m = 0; m < r.metrics.size(); ++m) {
      std::vector<double> xs;
      for (std::size_t i : s.points)
        if (r.values[i][m]) xs.push_back(*r.values[i][m]);
      s.stats.push_back(Summarise(xs));
    }
  r.varies.assign(r.in.parameters.size(), false);
  for (std::size_t p = 0; p < r.varies.size(); ++p)
    for (const auto& s : r.settings)
      if (s.value_index[p] != r.settings.front().value_index[p]) r.varies[p] = true;
}

// ---------------------------------------------------------------------------
// Input checks (all before anything is written)

std::invalid_argument Invalid(const std::string& what) {
  return std::invalid_argument("sweep report: " + what);
}

void CheckPoints(const SweepReportInputs& in) {
  for (const auto& p : in.points) {
    if (p.value_index.size() != in.parameters.size())
      throw Invalid("point " + p.id + " has " + std::to_string(p.value_index.size()) +
                    " value indices for " + std::to_string(in.parameters.size()) + " parameters");
    for (std::size_t k = 0; k < p.value_index.size(); ++k)
      if (p.value_index[k] < 0 ||
          static_cast<std::size_t>(p.value_index[k]) >= in.parameters[k].labels.size())
        throw Invalid("point " + p.id + ": no value " + std::to_string(p.value_index[k]) +
                      " of parameter " + in.parameters[k].name);
  }
}

void CheckAxes(const SweepReportInputs& in) {
  std::set<std::string> stems;
  for (const auto& a : in.axes) {
    const bool bad_stem = a.stem.empty() || a.stem == "." || a.stem == ".." ||
                          a.stem.find('/') != std::string::npos || CleanCell(a.stem) != a.stem;
    if (bad_stem) throw Invalid("axis stem \"" + CleanCell(a.stem) + "\" is not a plain file stem");
    if (!stems.insert(a.stem).second) throw Invalid("two axes named \"" + a.stem + "\"");
    if (a.parameter < 0 || static_cast<std::size_t>(a.parameter) >= in.parameters.size())
      throw Invalid("axis " + a.stem + ": no parameter " + std::to_string(a.parameter));
    const auto& labels = in.parameters[a.parameter].labels;
    for (const auto& [v, x] : a.x_of_value) {
      if (v < 0 || static_cast<std::size_t>(v) >= labels.size())
        throw Invalid("axis " + a.stem + ": no value " + std::to_string(v));
      if (!std::isfinite(x) || (a.log_x && x <= 0.0))
        throw Invalid("axis " + a.stem + ": x " + ShortestNumber(x) + " cannot be drawn");
    }
  }
}

// Throws if two columns of a header share a name.
void CheckUnique(const std::vector<std::string>& columns, const char* file) {
  std::set<std::string> seen;
  for (const auto& c : columns)
    if (!seen.insert(c).second)
      throw Invalid(std::string(file) + ": two columns named \"" + c + "\"");
}

// ---------------------------------------------------------------------------
// The tables

CsvTable SummaryTable(const Report& r) {
  std::vector<std::string> header{"point"};
  for (const auto& p : r.in.parameters) header.push_back(CleanCell(p.name));
  header.push_back("seed");
  for (const auto& m : r.metrics) header.push_back(m.name);
  CheckUnique(header, "summary.csv");
  CsvTable t(header);
  for (std::size_t i = 0; i < r.in.points.size(); ++i) {
    const SweepPoint& p = r.in.points[i];
    std::vector<std::string> row{CleanCell(p.id)};
    for (std::size_t k = 0; k < p.value_index.size(); ++k)
      row.push_back(CleanCell(r.in.parameters[k].labels[p.value_index[k]]));
    row.push_back(std::to_string(p.seed));
    for (const auto& v : r.values[i]) row.push_back(Cell(v));
    t.AddRow(row);
  }
  return t;
}

CsvTable AggregateTable(const Report& r) {
  std::vector<std::string> header;
  for (const auto& p : r.in.parameters) header.push_back(CleanCell(p.name));
  header.push_back("seeds");
  for (const auto& m : r.metrics) {
    header.push_back(m.name + "_mean");
    header.push_back(m.name + "_ci95");
  }
  CheckUnique(header, "aggregate.csv");
  CsvTable t(header);
  for (const auto& s : r.settings) {
    std::vector<std::string> row;
    for (std::size_t k = 0; k < s.value_index.size(); ++k)
      row.push_back(CleanCell(r.in.parameters[k].labels[s.value_index[k]]));
    row.push_back(std::to_string(s.points.size()));
    for (const auto& st : s.stats) {
      row.push_back(Cell(st.mean));
      row.push_back(Cell(st.ci95));
    }
    t.AddRow(row);
  }
  return t;
}

// ---------------------------------------------------------------------------
// The plots: long CSVs "x,y,ci95,series" drawn by PlotCsv

CsvTable CurveTable() { return CsvTable({"x", "y", "ci95", "series"}); }

// The common look: error bars from ci95, a line per series, missing means
// left out, y from 0, the legend below.
PlotSpec CurveSpec(std::string title, std::string x_label, std::string y_label) {
  PlotSpec spec;
  spec.title = std::move(title);
  spec.x_label = std::move(x_label);
  spec.y_label = std::move(y_label);
  spec.x_column = "x";
  spec.y_column = "y";
  spec.y_error_column = "ci95";
  spec.group_column = "series";
  spec.skip_empty_y = true;
  spec.y_min_zero = true;
  spec.key_below = true;  // many series: a legend inside would hide curves
  spec.height_px = 640;
  return spec;
}

// Writes plots/<name>.csv and draws plots/<name>.png beside it; a plot that
// cannot be drawn adds PlotCsv's message to `failures`.
void WritePlot(const fs::path& plots, const std::string& name, const CsvTable& csv,
               const PlotSpec& spec, std::vector<std::string>* failures) {
  const std::string csv_path = (plots / (name + ".csv")).string();
  WriteFileAtomic(csv_path, csv.str());
  if (std::string err = PlotCsv(csv_path, spec); !err.empty()) failures->push_back(std::move(err));
}

// The values of the axis's parameter that some setting has, with their x,
// ascending in x.
std::vector<std::pair<int, double>> AxisValuesPresent(const Report& r, const SweepAxis& a) {
  std::vector<std::pair<int, double>> out;
  for (const auto& [v, x] : a.x_of_value) {
    bool present = false;
    for (const auto& s : r.settings) present = present || s.value_index[a.parameter] == v;
    if (present) out.emplace_back(v, x);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& l, const auto& u) { return l.second < u.second; });
  return out;
}

// The combinations of the other parameters' values met on the axis (the
// axis parameter's own index set to -1), in order of first appearance.
std::vector<std::vector<int>> OtherCombinations(const Report& r, const SweepAxis& a,
                                                const std::vector<std::pair<int, double>>& xs) {
  std::vector<std::vector<int>> combos;
  std::set<std::vector<int>> seen;
  for (const auto& s : r.settings) {
    bool on_axis = false;
    for (const auto& vx : xs) on_axis = on_axis || s.value_index[a.parameter] == vx.first;
    if (!on_axis) continue;
    std::vector<int> combo = s.value_index;
    combo[a.parameter] = -1;
    if (seen.insert(combo).second) combos.push_back(combo);
  }
  return combos;
}

// "<key>, name=label, ..." over the other parameters that vary (as a cell:
// the commas become ';').
std::string SeriesLabel(const Report& r, const std::string& key, const std::vector<int>& combo) {
  std::string label = key;
  for (std::size_t k = 0; k < combo.size(); ++k)
    if (combo[k] >= 0 && r.varies[k])
      label += ", " + r.in.parameters[k].name + "=" + r.in.parameters[k].labels[combo[k]];
  return CleanCell(label);
}

// Adds to `t` metric m's curve along axis `a` at the other parameters'
// values `combo`: a row "x,mean,ci95" + `tail` per axis value that has a
// setting (an empty mean where no point of it has a value), or nothing if
// the metric has no value anywhere on it.
void AddCurve(const Report& r, const SweepAxis& a, std::size_t m, const std::vector<int>& combo,
              const std::vector<std::pair<int, double>>& xs, const std::vector<std::string>& tail,
              CsvTable* t) {
  std::vector<std::vector<std::string>> rows;
  bool any = false;  // a series with no value at all is left out
  for (const auto& [v, x] : xs) {
    std::vector<int> vi = combo;
    vi[a.parameter] = v;
    const auto it = r.setting_of.find(vi);
    if (it == r.setting_of.end()) continue;
    const Stats& st = r.settings[it->second].stats[m];
    any = any || st.mean.has_value();
    rows.push_back({ShortestNumber(x), Cell(st.mean), Cell(st.ci95)});
    rows.back().insert(rows.back().end(), tail.begin(), tail.end());
  }
  if (any)
    for (const auto& row : rows) t->AddRow(row);
}

// The curves of every metric of `kind` along axis `a`: a series per metric
// and combination of the other parameters, a row per axis value that has a
// setting (an empty y where no point of it has a value).
CsvTable AxisCurves(const Report& r, const SweepAxis& a, Kind kind,
                    const std::vector<std::pair<int, double>>& xs) {
  CsvTable t = CurveTable();
  const auto combos = OtherCombinations(r, a, xs);
  for (std::size_t m = 0; m < r.metrics.size(); ++m) {
    if (r.metrics[m].kind != kind) continue;
    for (const auto& combo : combos)
      AddCurve(r, a, m, combo, xs, {SeriesLabel(r, r.metrics[m].key, combo)}, &t);
  }
  return t;
}

// Whether the y column of a curve table is all > 0 and spans a factor of 20
// or more.
bool SpansDecades(const CsvTable& curves) {
  std::istringstream in(curves.str());
  std::string line;
  std::getline(in, line);  // header x,y,ci95,series
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  while (std::getline(in, line)) {
    const auto a = line.find(','), b = line.find(',', a + 1);
    double y = 0.0;
    if (a == std::string::npos || b == a + 1) continue;  // missing y
    if (!ParseFiniteNumber(line.substr(a + 1, b - a - 1), &y) || y <= 0.0) return false;
    lo = std::min(lo, y), hi = std::max(hi, y);
  }
  return hi > 0.0 && hi / lo >= 20.0;
}

// rmse_<stem>, coverage_<stem> and delivery_<stem> for each axis with two or
// more x values.
void WriteAxisPlots(const Report& r, const fs::path& plots, std::vector<std::string>* failures) {
  struct Family {
    Kind kind;
    const char* prefix;
    const char* what;
    const char* y_label;
  };
  const Family families[] = {
      {Kind::kRmse, "rmse_", "localisation RMSE", "RMSE (m)"},
      {Kind::kCoverage, "coverage_", "estimate coverage", "Windows with an estimate (share)"},
      {Kind::kDelivery, "delivery_", "delivery ratio", "Delivery ratio (on time / sent)"},
      {Kind::kGospa, "gospa_", "GOSPA (RMS over windows)", "GOSPA (m)"},
  };
  for (const auto& a : r.in.axes) {
    const auto xs = AxisValuesPresent(r, a);
    if (xs.size() < 2) continue;
    for (const auto& f : families) {
      const CsvTable csv = AxisCurves(r, a, f.kind, xs);
      if (csv.rows() == 0) continue;  // no value of this family at all
      PlotSpec spec = CurveSpec(Titled(r.in.title, std::string(f.what) + " vs " + a.x_label +
                                                       " (mean, 95 % CI over seeds)"),
                                a.x_label, f.y_label);
      spec.log_x = a.log_x;
      // RMSEs that span decades (a diverged filter beside a good one) on a
      // logarithmic axis, so that every curve stays readable.
      spec.log_y = f.kind == Kind::kRmse && SpansDecades(csv);
      WritePlot(plots, f.prefix + a.stem, csv, spec, failures);
    }
  }
}

// "name=label, name=label" for a setting.
std::string SettingText(const Report& r, const Setting& s) {
  std::string text;
  for (std::size_t k = 0; k < s.value_index.size(); ++k)
    text += (k ? ", " : "") + r.in.parameters[k].name + "=" +
            r.in.parameters[k].labels[s.value_index[k]];
  return text;
}

// rate_snr_<kkk> per setting: mean rate vs SNR, a line per beam.
void WriteRatePlots(const Report& r, const fs::path& plots, std::vector<std::string>* failures) {
  for (std::size_t k = 0; k < r.settings.size(); ++k) {
    const Setting& s = r.settings[k];
    CsvTable csv = CurveTable();
    for (std::size_t m = 0; m < r.metrics.size(); ++m)
      if (r.metrics[m].kind == Kind::kRate)
        csv.AddRow({r.metrics[m].snr_text, Cell(s.stats[m].mean), Cell(s.stats[m].ci95),
                    CleanCell(r.metrics[m].key)});
    if (csv.rows() == 0) return;  // no rates in the whole sweep
    const std::string setting = SettingText(r, s);
    const PlotSpec spec =
        CurveSpec(Titled(r.in.title,
                         "achievable rate vs SNR" + (setting.empty() ? "" : " (" + setting + ")")),
                  "SNR (dB)", "Rate (bit/s/Hz)");
    char name[32];
    std::snprintf(name, sizeof name, "rate_snr_%03zu", k);
    WritePlot(plots, name, csv, spec, failures);
  }
}

// ---------------------------------------------------------------------------
// Small multiples: long CSVs "x,y,ci95,series,panel" drawn by PlotPanels

// A figure of report.html: its PNG and CSV relative to the sweep folder, a
// caption and, when it could not be drawn, why.
struct Figure {
  std::string png, csv, caption, missing;
};

CsvTable PanelTable() { return CsvTable({"x", "y", "ci95", "series", "panel"}); }

// "name=label, name=label" over the parameters that vary, at `value_index`
// (an index < 0 is left out).
std::string VaryingText(const Report& r, const std::vector<int>& value_index) {
  std::string text;
  for (std::size_t k = 0; k < value_index.size(); ++k)
    if (value_index[k] >= 0 && r.varies[k])
      text += (text.empty() ? "" : ", ") + r.in.parameters[k].name + "=" +
              r.in.parameters[k].labels[value_index[k]];
  return text;
}

// A label as words inside a sentence: "Uplink loss" -> "uplink loss" (not
// "SNR (dB)").
std::string MidSentence(std::string label) {
  if (label.size() >= 2 && std::isupper(static_cast<unsigned char>(label[0])) &&
      std::islower(static_cast<unsigned char>(label[1])))
    label[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(label[0])));
  return label;
}

// The names of the parameters that vary, but `except`, as "a and b" ("" if
// none).
std::string VaryingNames(const Report& r, int except) {
  std::vector<std::string> names;
  for (std::size_t k = 0; k < r.varies.size(); ++k)
    if (r.varies[k] && static_cast<int>(k) != except) names.push_back(r.in.parameters[k].name);
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i)
    text += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
  return text;
}

// "3 seeds" or "1 to 3 seeds": the points per setting.
std::string SeedsText(const Report& r) {
  std::size_t lo = std::numeric_limits<std::size_t>::max(), hi = 0;
  for (const auto& s : r.settings)
    lo = std::min(lo, s.points.size()), hi = std::max(hi, s.points.size());
  if (r.settings.empty()) return "no seeds";
  const std::string n =
      lo == hi ? std::to_string(hi) : std::to_string(lo) + " to " + std::to_string(hi);
  return n + (hi == 1 ? " seed" : " seeds");
}

// The panels of every metric of `kind` along axis `a`: a panel per
// combination of the other parameters (in order of first appearance), in it
// a series per metric with some value there, a row per axis value that has
// a setting (an empty y where no point of it has a value).
CsvTable AxisPanels(const Report& r, const SweepAxis& a, Kind kind,
                    const std::vector<std::pair<int, double>>& xs) {
  CsvTable t = PanelTable();
  for (const auto& combo : OtherCombinations(r, a, xs)) {
    const std::string panel = CleanCell(VaryingText(r, combo));
    for (std::size_t m = 0; m < r.metrics.size(); ++m) {
      if (r.metrics[m].kind != kind) continue;
      AddCurve(r, a, m, combo, xs, {CleanCell(r.metrics[m].key), panel}, &t);
    }
  }
  return t;
}

// Writes plots/<name>.csv, draws plots/<name>.png beside it and returns the
// figure; a plot that cannot be drawn adds PlotPanels' message to `failures`.
Figure WritePanels(const fs::path& plots, const std::string& name, const CsvTable& csv,
                   const PanelPlotSpec& spec, std::string caption,
                   std::vector<std::string>* failures) {
  const std::string csv_path = (plots / (name + ".csv")).string();
  WriteFileAtomic(csv_path, csv.str());
  Figure f{"plots/" + name + ".png", "plots/" + name + ".csv", std::move(caption), ""};
  f.missing = PlotPanels(csv_path, spec);
  if (!f.missing.empty()) failures->push_back(f.missing);
  return f;
}

// One family of panel figures: a heading, what its y is, and its figures.
struct Section {
  std::string heading;
  std::vector<Figure> figures;
};

// panels_rmse_<stem>, panels_coverage_<stem> and panels_delivery_<stem> for
// each axis with two or more x values, as sections of the report.
std::vector<Section> WriteAxisPanels(const Report& r, const fs::path& plots,
                                     std::vector<std::string>* failures) {
  struct Family {
    Kind kind;
    const char* prefix;
    const char* heading;
    const char* what;  // for titles and captions
    const char* y_label;
    const char* legend;
    bool share;  // a share in [0, 1]
  };
  const Family families[] = {
      {Kind::kRmse, "panels_rmse_", "Localisation RMSE", "localisation RMSE", "RMSE (m)", "method",
       false},
      {Kind::kCoverage, "panels_coverage_", "Coverage: windows with an estimate",
       "share of windows with an estimate", "Windows with an estimate (share)", "method", true},
      {Kind::kDelivery, "panels_delivery_", "Uplink delivery", "uplink delivery ratio",
       "Delivery ratio (on time / sent)", "modality", true},
      {Kind::kGospa, "panels_gospa_", "Several targets: GOSPA", "GOSPA (RMS over windows)",
       "GOSPA (m)", "method", false},
  };
  std::vector<Section> sections;
  for (const auto& f : families) {
    Section section{f.heading, {}};
    for (const auto& a : r.in.axes) {
      const auto xs = AxisValuesPresent(r, a);
      if (xs.size() < 2) continue;
      const CsvTable csv = AxisPanels(r, a, f.kind, xs);
      if (csv.rows() == 0) continue;  // no value of this family at all
      const std::string others = VaryingNames(r, a.parameter);
      PanelPlotSpec spec;
      spec.title = Titled(r.in.title, std::string(f.what) + " vs " + MidSentence(a.x_label) +
                                          (others.empty() ? "" : ", one panel per " + others));
      spec.x_label = a.x_label;
      spec.y_label = f.y_label;
      spec.legend_title = f.legend;
      spec.log_x = a.log_x;
      // RMSEs that span decades (a diverged filter beside a good one) on a
      // logarithmic axis, so that every curve stays readable.
      spec.log_y = f.kind == Kind::kRmse && SpansDecades(csv);
      spec.y_min_zero = true;
      if (f.share) spec.y_max = 1.0;
      std::string caption = std::string(1, static_cast<char>(std::toupper(f.what[0]))) +
                            (f.what + 1) + " of each " + f.legend + " against " +
                            MidSentence(a.x_label) +
                            (others.empty() ? "" : ", one panel per " + others) +
                            ". Line: the mean over the " + SeedsText(r) +
                            " of each setting; shaded band: its 95 % confidence interval "
                            "(Student t); a point left out: no seed had a value.";
      if (spec.log_y)
        caption +=
            " Logarithmic y axis (the values span more than a factor of 20): a band that reaches "
            "0 runs down to the bottom.";
      section.figures.push_back(
          WritePanels(plots, f.prefix + a.stem, csv, spec, std::move(caption), failures));
    }
    if (!section.figures.empty()) sections.push_back(std::move(section));
  }
  return sections;
}

// panels_rate_snr: rate vs SNR, a panel per setting, a series per beam.
std::vector<Section> WriteRatePanels(const Report& r, const fs::path& plots,
                                     std::vector<std::string>* failures) {
  CsvTable csv = PanelTable();
  for (const Setting& s : r.settings) {
    std::string panel = VaryingText(r, s.value_index);
    if (panel.empty()) panel = SettingText(r, s);
    for (std::size_t m = 0; m < r.metrics.size(); ++m)
      if (r.metrics[m].kind == Kind::kRate)
        csv.AddRow({r.metrics[m].snr_text, Cell(s.stats[m].mean), Cell(s.stats[m].ci95),
                    CleanCell(r.metrics[m].key), CleanCell(panel)});
  }
  if (csv.rows() == 0) return {};  // no rates in the whole sweep
  PanelPlotSpec spec;
  spec.title = Titled(r.in.title, "achievable rate vs SNR, one panel per setting");
  spec.x_label = "SNR (dB)";
  spec.y_label = "Rate (bit/s/Hz)";
  spec.legend_title = "beam";
  spec.y_min_zero = true;
  std::string caption =
      "Achievable rate of the base station's beam to the UAV against SNR, the beam steered at "
      "each method's estimate (perfect: at the true position), one panel per setting. Line: "
      "the mean over the " +
      SeedsText(r) + " of each setting; shaded band: its 95 % confidence interval.";
  return {{"Achievable rate vs SNR",
           {WritePanels(plots, "panels_rate_snr", csv, spec, std::move(caption), failures)}}};
}

// ---------------------------------------------------------------------------
// report.html

// "mean ± ci95" to 3 significant digits of the mean (3 decimals for a
// share), the interval to as many decimals; "–" without a value.
std::string MeanCi(const Stats& st, bool share) {
  if (!st.mean) return "\u2013";
  int decimals = 3;
  if (!share && *st.mean != 0.0)
    decimals = std::clamp(2 - static_cast<int>(std::floor(std::log10(std::abs(*st.mean)))), 0, 6);
  std::string text = FormatFixed(*st.mean, decimals);
  if (st.ci95) text += " \u00b1 " + FormatFixed(*st.ci95, decimals);
  return text;
}

// A row per setting: the parameters that vary (all if none does), seeds,
// then "mean ± ci95" per metric of `kind`. Empty if there is no such metric.
std::vector<std::vector<std::string>> SettingTable(const Report& r, Kind kind, bool share) {
  std::vector<std::size_t> shown, metrics;
  for (std::size_t k = 0; k < r.in.parameters.size(); ++k)
    if (r.varies[k]) shown.push_back(k);
  if (shown.empty())
    for (std::size_t k = 0; k < r.in.parameters.size(); ++k) shown.push_back(k);
  for (std::size_t m = 0; m < r.metrics.size(); ++m)
    if (r.metrics[m].kind == kind) metrics.push_back(m);
  if (metrics.empty()) return {};
  std::vector<std::vector<std::string>> rows(1);
  for (std::size_t k : shown) rows[0].push_back(r.in.parameters[k].name);
  rows[0].push_back("seeds");
  for (std::size_t m : metrics) rows[0].push_back(r.metrics[m].key);
  for (const Setting& s : r.settings) {
    std::vector<std::string> row;
    for (std::size_t k : shown) row.push_back(r.in.parameters[k].labels[s.value_index[k]]);
    row.push_back(std::to_string(s.points.size()));
    for (std::size_t m : metrics) row.push_back(MeanCi(s.stats[m], share));
    rows.push_back(std::move(row));
  }
  return rows;
}

// The keys of the metrics of `kind`, ", "-separated.
std::string KeysText(const Report& r, Kind kind) {
  std::string text;
  std::set<std::string> seen;
  for (const auto& m : r.metrics)
    if (m.kind == kind && seen.insert(m.key).second) text += (text.empty() ? "" : ", ") + m.key;
  return text;
}

std::string ReportPage(const Report& r, const std::vector<Section>& sections) {
  HtmlPage page(r.in.title.empty() ? "Sweep report" : "Sweep " + r.in.title);
  page.Heading("What varied");
  std::string overview = std::to_string(r.in.points.size()) +
                         " points: " + std::to_string(r.settings.size()) + " settings (" +
                         (VaryingNames(r, -1).empty() ? "nothing varies" : VaryingNames(r, -1)) +
                         ") \u00d7 " + SeedsText(r) + " per setting.";
  page.Paragraph(overview);
  std::vector<std::vector<std::string>> parameters{{"parameter", "values", "count"}};
  for (const auto& p : r.in.parameters) {
    std::string labels;
    for (const auto& l : p.labels) labels += (labels.empty() ? "" : "; ") + l;
    parameters.push_back({p.name, labels, std::to_string(p.labels.size())});
  }
  page.Table(parameters);
  const std::string methods = KeysText(r, Kind::kRmse), modalities = KeysText(r, Kind::kDelivery);
  if (!methods.empty()) page.Paragraph("Methods: " + methods + ".");
  if (!modalities.empty()) page.Paragraph("Modalities on the uplink: " + modalities + ".");
  page.RawParagraph("Tables: " + HtmlLink("summary.csv", "summary.csv") +
                    " (a row per point) and " + HtmlLink("aggregate.csv", "aggregate.csv") +
                    " (a row per setting: mean and 95 % confidence interval over its seeds).");
  page.Paragraph(
      "Each figure is a grid of panels that share their axes, so that panels compare at a "
      "glance; a curve keeps its colour and marker in every panel, named in the legend below "
      "the panels. A line joins the mean over the seeds of each setting; the shaded band around "
      "it is the 95 % confidence interval of that mean (none with a single seed).");
  for (const Section& s : sections) {
    page.Heading(s.heading);
    for (const Figure& f : s.figures) {
      page.Figure(f.png, f.caption, f.missing);
      page.RawParagraph("Data: " + HtmlLink(f.csv, f.csv));
    }
  }
  const struct {
    Kind kind;
    const char* heading;
    bool share;
  } tables[] = {
      {Kind::kRmse, "RMSE per setting (m, mean \u00b1 95 % CI over seeds)", false},
      {Kind::kCoverage, "Coverage per setting (share of windows, mean \u00b1 95 % CI)", true},
      {Kind::kDelivery, "Delivery per setting (on time / sent, mean \u00b1 95 % CI)", true},
      {Kind::kGospa, "GOSPA per setting (m, mean \u00b1 95 % CI over seeds)", false},
  };
  bool explained = false;
  for (const auto& t : tables) {
    const auto rows = SettingTable(r, t.kind, t.share);
    if (rows.empty()) continue;
    page.Heading(t.heading);
    if (!explained)
      page.Paragraph(
          "Mean \u00b1 half-width of its 95 % confidence interval over the seeds that have a "
          "value; a value without \u00b1: one seed had one; \u2013: none had. seeds: the "
          "points of the setting.");
    explained = true;
    page.Table(rows);
  }
  return page.str();
}

}  // namespace

std::vector<std::string> WriteSweepReport(const std::string& dir, const SweepReportInputs& in) {
  CheckPoints(in);
  CheckAxes(in);
  std::vector<PointRates> rates;
  for (const auto& p : in.points) rates.push_back(ParseRateSnr(p));
  Report r{in, CollectMetrics(in, rates), {}, {}, {}, {}};
  for (std::size_t i = 0; i < in.points.size(); ++i) {
    r.values.emplace_back();
    for (const auto& m : r.metrics) r.values.back().push_back(ValueOf(in.points[i], rates[i], m));
  }
  GroupSettings(r);
  const CsvTable summary = SummaryTable(r);
  const CsvTable aggregate = AggregateTable(r);

  const fs::path root(dir);
  WriteFileAtomic((root / "summary.csv").string(), summary.str());
  WriteFileAtomic((root / "aggregate.csv").string(), aggregate.str());
  const fs::path plots = root / "plots";
  std::error_code ec;
  fs::create_directories(plots, ec);
  if (ec) throw std::runtime_error(plots.string() + ": cannot create folder: " + ec.message());
  std::vector<std::string> failures;
  WriteAxisPlots(r, plots, &failures);
  WriteRatePlots(r, plots, &failures);
  std::vector<Section> sections = WriteAxisPanels(r, plots, &failures);
  for (Section& s : WriteRatePanels(r, plots, &failures)) sections.push_back(std::move(s));
  WriteFileAtomic((root / "report.html").string(), ReportPage(r, sections));
  return failures;
}

double StudentT975(int dof) {
  if (dof < 1)
    throw std::invalid_argument("StudentT975: degrees of freedom must be >= 1, got " +
                                std::to_string(dof));
  return StudentTQuantile(dof, 0.975);
}

double StudentTQuantile(int dof, double p) {
  if (dof < 1 || !(p > 0.0 && p < 1.0))
    throw std::invalid_argument("StudentTQuantile: needs dof >= 1 and p in (0, 1), got dof " +
                                std::to_string(dof) + ", p " + std::to_string(p));
  return boost::math::quantile(boost::math::students_t_distribution<double>(dof), p);
}

}  // namespace uavsim::results
