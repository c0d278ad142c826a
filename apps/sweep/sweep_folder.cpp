#include "apps/sweep/sweep_folder.h"

#include <filesystem>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "results/sweep_report.h"

namespace uavsim::sim {
namespace {

namespace fs = std::filesystem;
using core::Json;

// rate_snr_targets.csv's sum rows ("snr_db,beam,sum,rate") as rate_snr.csv
// rows of a beam "sum_<beam>" (several targets: the sum rate of every
// target's beam), so the report tabulates and draws them beside the beams.
std::string SumRateRows(const std::string& targets_csv) {
  std::string out;
  std::size_t start = targets_csv.find('\n');  // past the header
  while (start != std::string::npos && start + 1 < targets_csv.size()) {
    const std::size_t end = targets_csv.find('\n', start + 1);
    const std::string line = targets_csv.substr(
        start + 1, end == std::string::npos ? std::string::npos : end - start - 1);
    start = end;
    const std::size_t a = line.find(','), b = line.find(',', a + 1), c = line.find(',', b + 1);
    if (c == std::string::npos || line.compare(b + 1, c - b - 1, "sum") != 0) continue;
    out += line.substr(0, a) + ",sum_" + line.substr(a + 1, b - a - 1) + line.substr(c) + "\n";
  }
  return out;
}

// The report's inputs from sweep.json (points' metrics read separately).
results::SweepReportInputs ReportLayout(const Json& r, const std::string& where) {
  results::SweepReportInputs in;
  try {
    in.title = r.at("name").get<std::string>();
    for (const Json& p : r.at("parameters"))
      in.parameters.push_back(
          {p.at("name").get<std::string>(), p.at("labels").get<std::vector<std::string>>()});
    for (const Json& a : r.at("axes")) {
      results::SweepAxis axis;
      axis.stem = a.at("stem").get<std::string>();
      axis.x_label = a.at("x_label").get<std::string>();
      axis.parameter = a.at("parameter").get<int>();
      for (const Json& xv : a.at("x_of_value"))
        axis.x_of_value.emplace_back(xv.at(0).get<int>(), xv.at(1).get<double>());
      axis.log_x = a.at("log_x").get<bool>();
      in.axes.push_back(std::move(axis));
    }
    for (const Json& p : r.at("points")) {
      results::SweepPoint pt;
      pt.id = p.at("id").get<std::string>();
      pt.value_index = p.at("values").get<std::vector<int>>();
      pt.seed = p.at("seed").get<std::uint64_t>();
      in.points.push_back(std::move(pt));
    }
  } catch (const Json::exception& e) {
    throw core::UsageError(where + ": not a sweep record of this uavsim version (" + e.what() +
                           ")");
  }
  return in;
}

}  // namespace

Json SweepRecord(const SweepSpec& spec) {
  Json r = Json::object();
  r["format"] = kSweepFormat;
  r["name"] = spec.name;
  r["spec"] = spec.canonical;
  Json params = Json::array();
  for (const results::SweepParameter& p : spec.TableParameters())
    params.push_back({{"name", p.name}, {"labels", p.labels}});
  r["parameters"] = params;
  Json axes = Json::array();
  for (const results::SweepAxis& a : spec.Axes()) {
    Json xs = Json::array();
    for (const auto& [i, x] : a.x_of_value) xs.push_back({i, x});
    axes.push_back({{"stem", a.stem},
                    {"x_label", a.x_label},
                    {"parameter", a.parameter},
                    {"x_of_value", xs},
                    {"log_x", a.log_x}});
  }
  r["axes"] = axes;
  Json points = Json::array();
  for (const SweepPointSpec& p : spec.points)
    points.push_back({{"id", p.id}, {"values", p.value_index}, {"seed", p.seed}});
  r["points"] = points;
  return r;
}

std::string PointDir(const std::string& dir, const std::string& id) {
  return (fs::path(dir) / "points" / id).string();
}

bool PointDone(const std::string& dir, const std::string& id) {
  std::error_code ec;
  return fs::is_regular_file(fs::path(PointDir(dir, id)) / "metrics.json", ec);
}

SweepOutcome MergeSweep(const std::string& dir) {
  const fs::path file = fs::path(dir) / "sweep.json";
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    throw core::UsageError(dir + ": not a sweep folder (no sweep.json)");
  Json record;
  try {
    record = Json::parse(core::ReadFileBytes(file.string()));
  } catch (const Json::exception& e) {
    throw core::UsageError(file.string() + ": unreadable: " + e.what());
  }
  if (record.value("format", "") != kSweepFormat)
    throw core::UsageError(file.string() + ": not a " + std::string(kSweepFormat) + " record");
  results::SweepReportInputs in = ReportLayout(record, file.string());
  SweepOutcome out;
  out.points = in.points.size();
  std::vector<std::string> missing;
  for (const results::SweepPoint& p : in.points)
    if (!PointDone(dir, p.id)) missing.push_back(p.id);
  if (!missing.empty()) {
    std::string list;
    for (std::size_t i = 0; i < missing.size() && i < 5; ++i) list += (i ? ", " : "") + missing[i];
    if (missing.size() > 5) list += ", ...";
    throw core::UsageError(dir + ": " + std::to_string(missing.size()) + " of " +
                           std::to_string(out.points) + " points not finished (" + list +
                           "); run the remaining shards, or the sweep again, first");
  }
  for (results::SweepPoint& p : in.points) {
    const fs::path run(PointDir(dir, p.id));
    p.metrics = core::LoadJsonFile((run / "metrics.json").string());
    std::error_code e2;
    if (fs::is_regular_file(run / "rate_snr.csv", e2))
      p.rate_snr_csv = core::ReadFileBytes((run / "rate_snr.csv").string());
    if (fs::is_regular_file(run / "rate_snr_targets.csv", e2))
      p.rate_snr_csv += SumRateRows(core::ReadFileBytes((run / "rate_snr_targets.csv").string()));
  }
  out.already_done = out.points;
  out.warnings = results::WriteSweepReport(dir, in);
  out.reported = true;
  return out;
}

}  // namespace uavsim::sim
