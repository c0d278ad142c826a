// The run report: read the run's files, derive small tables under report/,
// draw them with gnuplot, and lay everything out in report.html.
#include "results/run_report.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <ostream>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/atomic_file.h"
#include "core/json_io.h"
#include "results/csv.h"
#include "results/gnuplot.h"
#include "results/gnuplot_figure.h"
#include "results/html.h"

namespace uavsim::results {
namespace {

namespace fs = std::filesystem;
using core::Json;

// ---------------------------------------------------------------------------
// Reading the run's CSVs

// A CSV file of the run (columns found by name); errors name the file.
struct Table : CsvFile {
  std::string name;  // for messages

  long Column(const std::string& column) const {
    const long c = CsvFile::Column(column);
    if (c < 0) throw std::invalid_argument(name + ": no column \"" + column + "\"");
    return c;
  }
  double Number(std::size_t row, long column) const {
    double x = 0.0;
    if (!ParseFiniteNumber(rows[row][static_cast<std::size_t>(column)], &x))
      throw std::invalid_argument(name + ": line " + std::to_string(line[row]) + ": \"" +
                                  header[static_cast<std::size_t>(column)] +
                                  "\" is not a finite number");
    return x;
  }
};

// The table in `dir`/`file`, or nothing if there is no such file.
std::optional<Table> ReadTable(const fs::path& dir, const std::string& file) {
  const fs::path path = dir / file;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return std::nullopt;
  Table t;
  if (std::string err = ReadCsvFile(path.string(), &t); !err.empty())
    throw std::invalid_argument(path.string() + ": " + err);
  t.name = path.string();
  return t;
}

// ---------------------------------------------------------------------------
// Small helpers

std::string Fixed(double x, int decimals) { return FormatFixed(x, decimals); }

// A JSON number as text with `decimals`, "-" for null or absent.
std::string JsonFixed(const Json& j, const std::string& key, int decimals) {
  if (!j.is_object() || !j.contains(key) || !j.at(key).is_number()) return "-";
  return Fixed(j.at(key).get<double>(), decimals);
}

std::string JsonText(const Json& j) {
  if (j.is_string()) return j.get<std::string>();
  if (j.is_null()) return "none";
  if (j.is_number_float()) return core::FormatNumber(j.get<double>());
  return j.dump();
}

// The value at `pointer` in `j`, or null.
Json At(const Json& j, const std::string& pointer) {
  const Json::json_pointer p(pointer);
  return j.contains(p) ? j.at(p) : Json(nullptr);
}

// Order statistic interpolation (as channel/edge_receiver.h's Percentile).
double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double h = (static_cast<double>(v.size()) - 1.0) * q;
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (h - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

constexpr const char* kModalities[] = {"camera", "lidar", "radar"};
constexpr const char* kModalityColours[] = {"#1f77b4", "#2ca02c", "#d62728"};
// Method colours, in the order methods first appear (then repeating).
constexpr const char* kMethodColours[] = {"#e6550d", "#3182bd", "#31a354", "#756bb1",
                                          "#de2d26", "#636363", "#8c6d31", "#e377c2"};

// ---------------------------------------------------------------------------
// The run's data, as read

struct Estimate {
  double t_s = 0.0;
  Eigen::Vector3d p;
  long track = 0;  // estimates.csv's track column (0: a single estimate, or none)
};

// One target's true path (truth.csv rows of one `target`).
struct TargetPath {
  std::string id;
  std::vector<double> t;
  std::vector<Eigen::Vector3d> p;
};

struct RunData {
  fs::path dir;
  Json manifest, metrics, scenario;
  std::optional<Table> truth, estimates, packets, world_top, layout, rate_snr, rate_snr_common;
  std::optional<Table> gospa, rate_snr_targets;  // several targets, or mtt
  std::vector<TargetPath> targets;               // several targets: each one's path
  std::vector<std::string> methods;              // in order of first appearance
  // Each method's estimate per window (a tracker's: its oldest track), and
  // a tracker's every track (estimates.csv's track column above 0).
  std::map<std::string, std::vector<Estimate>> estimated, tracked;
  std::vector<double> truth_t;
  std::vector<Eigen::Vector3d> truth_p;
  double window_s = 0.2, duration_s = 0.0;
};

// Each target's path from truth.csv's `target` column (several targets).
void LoadTargets(RunData& d) {
  const Table& truth = *d.truth;
  const long target = truth.CsvFile::Column("target");
  if (target < 0) return;
  const long t = truth.Column("t_s"), x = truth.Column("x_m"), y = truth.Column("y_m"),
             z = truth.Column("z_m");
  for (std::size_t i = 0; i < truth.rows.size(); ++i) {
    const std::string& id = truth.rows[i][static_cast<std::size_t>(target)];
    auto it = std::find_if(d.targets.begin(), d.targets.end(),
                           [&](const TargetPath& p) { return p.id == id; });
    if (it == d.targets.end()) it = d.targets.insert(d.targets.end(), TargetPath{id, {}, {}});
    it->t.push_back(truth.Number(i, t));
    it->p.emplace_back(truth.Number(i, x), truth.Number(i, y), truth.Number(i, z));
  }
}

RunData Load(const std::string& dir) {
  RunData d;
  d.dir = dir;
  for (const char* f : {"metrics.json", "manifest.json"}) {
    std::error_code ec;
    if (!fs::is_regular_file(d.dir / f, ec))
      throw std::invalid_argument(dir + ": not a run directory (no " + f + ")");
  }
  try {
    d.metrics = core::LoadJsonFile((d.dir / "metrics.json").string());
    d.manifest = core::LoadJsonFile((d.dir / "manifest.json").string());
  } catch (const std::exception& e) {
    throw std::invalid_argument(e.what());
  }
  d.scenario = d.manifest.value("scenario", Json::object());
  if (const Json w = At(d.scenario, "/pipeline/window_s"); w.is_number())
    d.window_s = w.get<double>();
  if (const Json t = At(d.scenario, "/duration_s"); t.is_number()) d.duration_s = t.get<double>();
  if (!(d.window_s > 0)) throw std::invalid_argument(dir + "/manifest.json: window_s must be > 0");
  d.truth = ReadTable(d.dir, "truth.csv");
  d.estimates = ReadTable(d.dir, "estimates.csv");
  d.packets = ReadTable(d.dir, "packets.csv");
  d.world_top = ReadTable(d.dir, "world_top.csv");
  d.layout = ReadTable(d.dir, "layout.csv");
  d.rate_snr = ReadTable(d.dir, "rate_snr.csv");
  d.rate_snr_common = ReadTable(d.dir, "rate_snr_common.csv");
  d.gospa = ReadTable(d.dir, "gospa.csv");
  d.rate_snr_targets = ReadTable(d.dir, "rate_snr_targets.csv");
  if (d.truth) LoadTargets(d);
  if (d.truth) {
    const long t = d.truth->Column("t_s"), x = d.truth->Column("x_m"), y = d.truth->Column("y_m"),
               z = d.truth->Column("z_m");
    // Several targets (a `target` column): the report follows the first,
    // the one the methods localize.
    const long target = d.truth->CsvFile::Column("target");
    for (std::size_t i = 0; i < d.truth->rows.size(); ++i) {
      if (target >= 0 && d.truth->rows[i][static_cast<std::size_t>(target)] !=
                             d.truth->rows[0][static_cast<std::size_t>(target)])
        continue;
      d.truth_t.push_back(d.truth->Number(i, t));
      d.truth_p.emplace_back(d.truth->Number(i, x), d.truth->Number(i, y), d.truth->Number(i, z));
      if (d.truth_t.size() > 1 && d.truth_t.back() <= d.truth_t[d.truth_t.size() - 2])
        throw std::invalid_argument(d.truth->name + ": line " + std::to_string(d.truth->line[i]) +
                                    ": t_s must increase");
    }
  }
  if (d.estimates) {
    const Table& e = *d.estimates;
    const long t = e.Column("t_s"), m = e.Column("method"), x = e.Column("x_m"),
               y = e.Column("y_m"), z = e.Column("z_m"), track = e.CsvFile::Column("track");
    for (std::size_t i = 0; i < e.rows.size(); ++i) {
      const std::string& method = e.rows[i][static_cast<std::size_t>(m)];
      if (!d.estimated.count(method)) d.methods.push_back(method);
      const Estimate est{e.Number(i, t),
                         Eigen::Vector3d(e.Number(i, x), e.Number(i, y), e.Number(i, z)),
                         track < 0 ? 0 : static_cast<long>(e.Number(i, track))};
      std::vector<Estimate>& one = d.estimated[method];
      if (est.track > 0) d.tracked[method].push_back(est);
      // A tracker's estimate is its oldest track (the lowest label) of the window.
      if (est.track > 0 && !one.empty() && one.back().t_s == est.t_s) {
        if (est.track < one.back().track) one.back() = est;
        continue;
      }
      one.push_back(est);
    }
  }
  // Methods that ran but never estimated still get a row in the tables.
  if (const Json rmse = d.metrics.value("rmse_m", Json::object()); rmse.is_object())
    for (const auto& [method, value] : rmse.items())
      if (std::find(d.methods.begin(), d.methods.end(), method) == d.methods.end())
        d.methods.push_back(method);
  return d;
}

// The truth at t_s, linear between samples (clamped at the ends).
std::optional<Eigen::Vector3d> TruthAt(const RunData& d, double t_s) {
  if (d.truth_t.empty()) return std::nullopt;
  const auto it = std::lower_bound(d.truth_t.begin(), d.truth_t.end(), t_s);
  if (it == d.truth_t.begin()) return d.truth_p.front();
  if (it == d.truth_t.end()) return d.truth_p.back();
  const std::size_t i = static_cast<std::size_t>(it - d.truth_t.begin());
  const double a = (t_s - d.truth_t[i - 1]) / (d.truth_t[i] - d.truth_t[i - 1]);
  return (1.0 - a) * d.truth_p[i - 1] + a * d.truth_p[i];
}

std::string MethodColour(const RunData& d, const std::string& method) {
  const auto it = std::find(d.methods.begin(), d.methods.end(), method);
  const std::size_t i = static_cast<std::size_t>(it - d.methods.begin());
  return kMethodColours[i % (sizeof kMethodColours / sizeof *kMethodColours)];
}

// ---------------------------------------------------------------------------
// Derived tables

struct Errors {
  CsvTable csv{{"t_s", "method", "error_m", "east_m", "north_m", "up_m"}};
  std::map<std::string, std::vector<std::pair<double, double>>> by_method;  // (t, |e|)
};

Errors ComputeErrors(const RunData& d) {
  Errors out;
  for (const std::string& method : d.methods) {
    const auto it = d.estimated.find(method);
    if (it == d.estimated.end()) continue;
    for (const Estimate& e : it->second) {
      const auto truth = TruthAt(d, e.t_s);
      if (!truth) continue;
      const Eigen::Vector3d err = e.p - *truth;
      out.by_method[method].emplace_back(e.t_s, err.norm());
      out.csv.AddRow({Fixed(e.t_s, 6), method, Fixed(err.norm(), 6), Fixed(err.x(), 6),
                      Fixed(err.y(), 6), Fixed(err.z(), 6)});
    }
  }
  return out;
}

struct Reception {
  long delivered = 0, late = 0, lost = 0, in_flight = 0;
  long sent() const { return delivered + late + lost + in_flight; }
};

const char* WindowState(const Reception& r) {
  if (r.sent() == 0) return "none_sent";
  if (r.delivered == r.sent()) return "on_time";
  if (r.delivered > 0) return "partly";
  if (r.late > 0) return "late";
  return "lost";
}

struct Packets {
  // [window][modality]
  std::vector<std::map<std::string, Reception>> windows;
  std::map<std::string, Reception> totals;
  std::map<std::string, std::vector<double>> latency_ms;
};

Packets CountPackets(const RunData& d) {
  Packets out;
  const Table& t = *d.packets;
  const long mc = t.Column("modality"), wc = t.Column("window"), sc = t.Column("status"),
             lc = t.Column("latency_s");
  long windows = static_cast<long>(std::llround(std::ceil(d.duration_s / d.window_s - 1e-9)));
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    windows = std::max(windows, static_cast<long>(t.Number(i, wc)) + 1);
  out.windows.resize(static_cast<std::size_t>(std::max(0L, windows)));
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const std::string& modality = t.rows[i][static_cast<std::size_t>(mc)];
    // Modality names go into a gnuplot data block (the bars' labels): plain
    // names only, so that no cell can end the block and become a command.
    if (modality.empty() || modality.size() > 64 ||
        modality.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                   "0123456789_-") != std::string::npos)
      throw std::invalid_argument(t.name + ": line " + std::to_string(t.line[i]) +
                                  ": a modality is 1 to 64 letters, digits, '_' or '-'");
    const double w = t.Number(i, wc);
    if (w < 0)
      throw std::invalid_argument(t.name + ": line " + std::to_string(t.line[i]) +
                                  ": negative window");
    const std::string& status = t.rows[i][static_cast<std::size_t>(sc)];
    Reception& r = out.windows[static_cast<std::size_t>(w)][modality];
    Reception& total = out.totals[modality];
    if (status == "delivered")
      ++r.delivered, ++total.delivered;
    else if (status == "late")
      ++r.late, ++total.late;
    else if (status == "lost")
      ++r.lost, ++total.lost;
    else if (status == "in_flight")
      ++r.in_flight, ++total.in_flight;
    else
      throw std::invalid_argument(t.name + ": line " + std::to_string(t.line[i]) +
                                  ": unknown status \"" + status + "\"");
    if (!t.rows[i][static_cast<std::size_t>(lc)].empty())
      out.latency_ms[modality].push_back(1000.0 * t.Number(i, lc));
  }
  return out;
}

// The modalities to show: the three of the paper in order, then any other.
std::vector<std::string> ModalityOrder(const Packets& p) {
  std::vector<std::string> out(std::begin(kModalities), std::end(kModalities));
  for (const auto& [m, r] : p.totals)
    if (std::find(out.begin(), out.end(), m) == out.end()) out.push_back(m);
  std::vector<std::string> present;
  for (const auto& m : out)
    if (p.totals.count(m)) present.push_back(m);
  return present;
}

std::string ModalityColour(const std::string& m, std::size_t index) {
  for (std::size_t i = 0; i < 3; ++i)
    if (m == kModalities[i]) return kModalityColours[i];
  return kMethodColours[index % (sizeof kMethodColours / sizeof *kMethodColours)];
}

// ---------------------------------------------------------------------------
// Figures

struct Figure {
  std::string png;  // relative to the run directory
  std::string caption;
  std::string missing;  // why it is not drawn ("" = drawn)
};

// Draws `figure` into dir/png; a failure becomes the figure's note and a
// warning.
Figure Draw(const RunData& d, const RunReportOptions& o, const std::string& png,
            const std::string& caption, const GnuplotFigure& figure, int width, int height,
            std::vector<std::string>* warnings) {
  GnuplotImage image;
  image.png_path = (d.dir / png).string();
  image.width_px = width;
  image.height_px = height;
  image.gnuplot = o.gnuplot;
  Figure f{png, caption, figure.Draw(image)};
  if (!f.missing.empty()) warnings->push_back(png + ": " + f.missing);
  return f;
}

Figure NotDrawn(const std::string& png, const std::string& caption, const std::string& why,
                std::vector<std::string>* warnings) {
  warnings->push_back(png + ": " + why);
  return {png, caption, why};
}

// The columns of layout.csv the top view reads.
struct LayoutColumns {
  long object = 0, kind = 0, x = 0, y = 0;
};

LayoutColumns ColumnsOf(const Table& layout) {
  return {layout.Column("object"), layout.Column("kind"), layout.Column("x_m"),
          layout.Column("y_m")};
}

// The part of the ground plane the top view must show.
struct Extent {
  Eigen::Vector2d lo, hi;
  void Add(double x, double y) {
    lo = lo.cwiseMin(Eigen::Vector2d(x, y));
    hi = hi.cwiseMax(Eigen::Vector2d(x, y));
  }
};

// The true path and the nodes (not their fields of view), starting from the
// path's first point (the origin without one).
Extent PathAndNodesExtent(const RunData& d, const Table& layout, const LayoutColumns& lc) {
  Eigen::Vector2d lo = Eigen::Vector2d::Zero();
  if (!d.truth_p.empty()) lo = d.truth_p.front().head<2>();
  Extent extent{lo, lo};
  for (const auto& p : d.truth_p) extent.Add(p.x(), p.y());
  for (std::size_t i = 0; i < layout.rows.size(); ++i)
    if (layout.rows[i][static_cast<std::size_t>(lc.kind)] != "fov")
      extent.Add(layout.Number(i, lc.x), layout.Number(i, lc.y));
  return extent;
}

// world_top.csv's cells as "x y height" rows by surface, with the grid's
// spacing and the tallest building's height.
struct WorldCells {
  double cell = 1.0, max_height = 1.0;
  std::string buildings, trees, poles;
};

WorldCells ReadWorldCells(const RunData& d) {
  WorldCells out;
  if (!d.world_top || d.world_top->rows.empty()) return out;
  const Table& w = *d.world_top;
  const long wx = w.Column("x_m"), wy = w.Column("y_m"), wh = w.Column("height_m"),
             ws = w.Column("surface");
  std::set<double> xs;
  for (std::size_t i = 0; i < w.rows.size() && xs.size() < 3; ++i) xs.insert(w.Number(i, wx));
  if (xs.size() >= 2) out.cell = *std::next(xs.begin()) - *xs.begin();
  for (std::size_t i = 0; i < w.rows.size(); ++i) {
    const double x = w.Number(i, wx), y = w.Number(i, wy), h = w.Number(i, wh);
    const std::string& s = w.rows[i][static_cast<std::size_t>(ws)];
    const std::string row =
        ShortestNumber(x) + " " + ShortestNumber(y) + " " + ShortestNumber(h) + "\n";
    if (s == "foliage")
      out.trees += row;
    else if (s == "metal")
      out.poles += row;
    else
      out.buildings += row, out.max_height = std::max(out.max_height, h);
  }
  // Cells lie on a grid: a smaller spacing among the first rows' xs.
  std::vector<double> sorted;
  for (std::size_t i = 0; i < std::min<std::size_t>(w.rows.size(), 400); ++i)
    sorted.push_back(w.Number(i, wx));
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 1; i < sorted.size(); ++i)
    if (sorted[i] - sorted[i - 1] > 1e-6) out.cell = std::min(out.cell, sorted[i] - sorted[i - 1]);
  return out;
}

// A square about `extent` at equal scales, the titles, and the palette of
// building heights.
void SetTopViewAxes(GnuplotFigure& figure, const RunData& d, const Extent& extent,
                    double max_height) {
  const Eigen::Vector2d centre = 0.5 * (extent.lo + extent.hi);
  const double half = 0.5 * (extent.hi - extent.lo).maxCoeff() + 3.0;
  figure.Commands()
      << "set size ratio -1\n"
      << "set xrange [" << ShortestNumber(centre.x() - half) << ":"
      << ShortestNumber(centre.x() + half) << "]\nset yrange [" << ShortestNumber(centre.y() - half)
      << ":" << ShortestNumber(centre.y() + half) << "]\n"
      << "set xlabel 'East x (m)'\nset ylabel 'North y (m)'\n"
      << "set title " << GnuplotString("Top view: " + d.scenario.value("name", std::string("run")))
      << "\n"
      << "set key outside right top box opaque\n"
      << "set grid front lc rgb '#bbbbbb'\n"
      << "set palette defined (0 '#e6e6e6', 1 '#4d4d4d')\n"
      << "set cbrange [0:" << ShortestNumber(max_height) << "]\n"
      << "set cblabel 'Building height (m)'\n"
      << "set colorbox vertical user origin screen 0.80, screen 0.12 size screen 0.02, screen 0.3\n"
      << "set style fill solid 1.0 noborder\n";
}

// Buildings shaded by height, trees and poles, as boxes a hair wider than a
// cell: no seams between cells.
void PlotWorldCells(GnuplotFigure& figure, const WorldCells& cells) {
  const std::string h = ShortestNumber(0.51 * cells.cell);
  if (!cells.buildings.empty()) {
    figure.Data("buildings", cells.buildings);
    figure.Curve("$buildings using 1:2:(" + h + "):(" + h + "):3 with boxxy fc palette notitle");
  }
  if (!cells.trees.empty()) {
    figure.Data("trees", cells.trees);
    figure.Curve("$trees using 1:2:(" + h + "):(" + h +
                 ") with boxxy fc rgb '#74c476' title 'trees'");
  }
  if (!cells.poles.empty()) {
    figure.Data("poles", cells.poles);
    figure.Curve("$poles using 1:2:(" + h + "):(" + h +
                 ") with boxxy fc rgb '#08306b' title 'poles'");
  }
}

// A label beside every node, in layout order; returns each node's kind by
// its name.
std::map<std::string, std::string> LabelNodes(GnuplotFigure& figure, const Table& layout,
                                              const LayoutColumns& lc) {
  std::map<std::string, std::string> node_kind;
  int label = 0;
  for (std::size_t i = 0; i < layout.rows.size(); ++i) {
    const std::string& object = layout.rows[i][static_cast<std::size_t>(lc.object)];
    const std::string& kind = layout.rows[i][static_cast<std::size_t>(lc.kind)];
    if (kind == "fov" || kind == "base_station") continue;
    node_kind[object] = kind;
    ++label;
    figure.Text("uavsim_label" + std::to_string(label), object);
    figure.Commands() << "set label " << label << " uavsim_label" << label << " at "
                      << ShortestNumber(layout.Number(i, lc.x)) << ","
                      << ShortestNumber(layout.Number(i, lc.y)) << " offset 1,-1 front font ',9'\n";
  }
  return node_kind;
}

// The fields of view (one block per node, in layout order), dashed in their
// node's modality colour.
void PlotFieldsOfView(GnuplotFigure& figure, const Table& layout, const LayoutColumns& lc,
                      const std::map<std::string, std::string>& node_kind) {
  std::vector<std::string> fov_objects;
  std::map<std::string, std::string> fov_rows;
  for (std::size_t i = 0; i < layout.rows.size(); ++i) {
    const std::string& object = layout.rows[i][static_cast<std::size_t>(lc.object)];
    if (layout.rows[i][static_cast<std::size_t>(lc.kind)] != "fov") continue;
    const std::string xy =
        ShortestNumber(layout.Number(i, lc.x)) + " " + ShortestNumber(layout.Number(i, lc.y));
    if (!fov_rows.count(object)) fov_objects.push_back(object);
    fov_rows[object] += xy + "\n";
  }
  for (std::size_t k = 0; k < fov_objects.size(); ++k) {
    const std::string& object = fov_objects[k];
    const auto kind = node_kind.count(object) ? node_kind.at(object) : std::string();
    std::size_t mi = 0;
    while (mi < 3 && kind != kModalities[mi]) ++mi;
    const std::string colour = mi < 3 ? kModalityColours[mi] : "#555555";
    figure.Data("fov" + std::to_string(k), fov_rows[object]);
    figure.Text("uavsim_fov" + std::to_string(k), object + " field of view");
    figure.Curve("$fov" + std::to_string(k) + " using 1:2 with lines dt 2 lw 1.5 lc rgb '" +
                 colour + "' title uavsim_fov" + std::to_string(k));
  }
}

// The true path, then each method's estimates.
void PlotPathAndEstimates(GnuplotFigure& figure, const RunData& d) {
  std::string truth;
  for (const auto& p : d.truth_p)
    truth += ShortestNumber(p.x()) + " " + ShortestNumber(p.y()) + "\n";
  figure.Data("truth", truth);
  figure.Curve("$truth using 1:2 with lines lw 2 lc rgb 'black' title 'truth'");
  std::size_t mk = 0;
  for (const std::string& method : d.methods) {
    const auto it = d.estimated.find(method);
    if (it == d.estimated.end()) continue;
    std::string rows;
    for (const Estimate& e : it->second)
      rows += ShortestNumber(e.p.x()) + " " + ShortestNumber(e.p.y()) + "\n";
    figure.Data("est" + std::to_string(mk), rows);
    figure.Text("uavsim_method" + std::to_string(mk), method);
    figure.Curve("$est" + std::to_string(mk) + " using 1:2 with points pt 7 ps 0.6 lc rgb '" +
                 MethodColour(d, method) + "' title uavsim_method" + std::to_string(mk));
    ++mk;
  }
}

// The nodes, a marker per modality, then the base station.
void PlotNodes(GnuplotFigure& figure, const Table& layout, const LayoutColumns& lc) {
  std::string nodes[3], base_station;
  for (std::size_t i = 0; i < layout.rows.size(); ++i) {
    const std::string& kind = layout.rows[i][static_cast<std::size_t>(lc.kind)];
    const std::string row = ShortestNumber(layout.Number(i, lc.x)) + " " +
                            ShortestNumber(layout.Number(i, lc.y)) + "\n";
    if (kind == "base_station") base_station += row;
    for (std::size_t m = 0; m < 3; ++m)
      if (kind == kModalities[m]) nodes[m] += row;
  }
  const char* node_points[] = {"5", "9", "13"};
  for (std::size_t m = 0; m < 3; ++m) {
    if (nodes[m].empty()) continue;
    figure.Data(std::string("node_") + kModalities[m], nodes[m]);
    figure.Curve(std::string("$node_") + kModalities[m] + " using 1:2 with points pt " +
                 node_points[m] + " ps 1.8 lc rgb '" + kModalityColours[m] + "' title '" +
                 kModalities[m] + " node'");
  }
  if (!base_station.empty()) {
    figure.Data("bs", base_station);
    figure.Curve(
        "$bs using 1:2 with points pt 3 ps 2.2 lw 2 lc rgb '#6a3d9a' title 'base station'");
  }
}

// The top view's map, fields of view and nodes, with `paths` drawing the
// paths and estimates over the map.
Figure TopViewWith(const RunData& d, const RunReportOptions& o, const std::string& png,
                   const std::string& caption, const std::function<void(GnuplotFigure&)>& paths,
                   std::vector<std::string>* warnings) {
  if (!d.layout || !d.truth)
    return NotDrawn(png, caption,
                    "the run has no " + std::string(!d.layout ? "layout.csv" : "truth.csv") +
                        " (made by an older uavsim)",
                    warnings);
  // The plotted square: the cells of world_top.csv, the nodes and the paths.
  const Table& layout = *d.layout;
  const LayoutColumns lc = ColumnsOf(layout);
  Extent extent = PathAndNodesExtent(d, layout, lc);
  for (const TargetPath& target : d.targets)
    for (const auto& p : target.p) extent.Add(p.x(), p.y());
  const WorldCells cells = ReadWorldCells(d);
  // The map's cells reach as far as the world_top.csv grid has anything.
  if (d.world_top)
    for (std::size_t i = 0; i < d.world_top->rows.size(); ++i)
      extent.Add(d.world_top->Number(i, d.world_top->Column("x_m")),
                 d.world_top->Number(i, d.world_top->Column("y_m")));
  GnuplotFigure figure;
  SetTopViewAxes(figure, d, extent, cells.max_height);
  PlotWorldCells(figure, cells);
  const std::map<std::string, std::string> node_kind = LabelNodes(figure, layout, lc);
  PlotFieldsOfView(figure, layout, lc, node_kind);
  paths(figure);
  PlotNodes(figure, layout, lc);
  figure.Plot();
  return Draw(d, o, png, caption, figure, 1000, 760, warnings);
}

Figure TopView(const RunData& d, const RunReportOptions& o, std::vector<std::string>* warnings) {
  return TopViewWith(
      d, o, "report/top_view.png",
      "Top view: buildings shaded by height, trees green; each node with its horizontal field of "
      "view (dashed: boresight azimuth +- half the field of view across the image or scan); the "
      "base station; the true path (black) and every method's estimates (dots)." +
          std::string(d.targets.size() > 1 ? " With several targets: the first one's path." : ""),
      [&](GnuplotFigure& figure) { PlotPathAndEstimates(figure, d); }, warnings);
}

// ---------------------------------------------------------------------------
// Several targets

constexpr const char* kTargetColours[] = {"#1b9e77", "#d95f02", "#7570b3", "#e7298a",
                                          "#66a61e", "#e6ab02", "#a6761d", "#17becf"};

std::string TargetColour(std::size_t k) {
  return kTargetColours[k % (sizeof kTargetColours / sizeof *kTargetColours)];
}

// The methods that report labelled tracks (a track column above 0).
std::vector<std::string> Trackers(const RunData& d) {
  std::vector<std::string> out;
  for (const std::string& m : d.methods)
    if (d.tracked.count(m)) out.push_back(m);
  return out;
}

// The target nearest p at t_s within c_m (its index), or -1.
long NearestTarget(const RunData& d, double t_s, const Eigen::Vector3d& p, double c_m) {
  long best = -1;
  double best_d = c_m;
  for (std::size_t k = 0; k < d.targets.size(); ++k) {
    const TargetPath& target = d.targets[k];
    const auto it = std::lower_bound(target.t.begin(), target.t.end(), t_s - 1e-9);
    if (it == target.t.end()) continue;
    const double dist = (target.p[static_cast<std::size_t>(it - target.t.begin())] - p).norm();
    if (dist < best_d) best = static_cast<long>(k), best_d = dist;
  }
  return best;
}

// Each target's path in its colour; the trackers' track points in the
// colour of the target nearest them (within GOSPA's c), grey beyond.
void PlotTargetsAndTracks(GnuplotFigure& figure, const RunData& d) {
  const double c_m =
      At(d.metrics, "/gospa/c_m").is_number() ? At(d.metrics, "/gospa/c_m").get<double>() : 10.0;
  std::vector<std::string> points(d.targets.size() + 1);
  for (const std::string& method : Trackers(d))
    for (const Estimate& e : d.tracked.at(method)) {
      const long k = NearestTarget(d, e.t_s, e.p, c_m);
      points[k < 0 ? d.targets.size() : static_cast<std::size_t>(k)] +=
          ShortestNumber(e.p.x()) + " " + ShortestNumber(e.p.y()) + "\n";
    }
  for (std::size_t k = 0; k < d.targets.size(); ++k) {
    std::string path;
    for (const auto& p : d.targets[k].p)
      path += ShortestNumber(p.x()) + " " + ShortestNumber(p.y()) + "\n";
    const std::string n = std::to_string(k);
    figure.Data("target" + n, path);
    figure.Text("uavsim_target" + n, d.targets[k].id);
    figure.Curve("$target" + n + " using 1:2 with lines lw 2 lc rgb '" + TargetColour(k) +
                 "' title uavsim_target" + n);
    if (points[k].empty()) continue;
    figure.Data("tracked" + n, points[k]);
    figure.Curve("$tracked" + n + " using 1:2 with points pt 7 ps 0.5 lc rgb '" + TargetColour(k) +
                 "' notitle");
  }
  if (!points.back().empty()) {
    figure.Data("false_tracks", points.back());
    figure.Curve(
        "$false_tracks using 1:2 with points pt 6 ps 0.5 lc rgb '#555555' title 'no target near'");
  }
}

Figure TargetsTopView(const RunData& d, const RunReportOptions& o,
                      std::vector<std::string>* warnings) {
  const std::vector<std::string> trackers = Trackers(d);
  std::string names;
  for (const std::string& m : trackers) names += (names.empty() ? "" : ", ") + m;
  return TopViewWith(
      d, o, "report/targets_top_view.png",
      "Several targets: each target's true path in its colour, and every track point of " +
          (names.empty() ? std::string("the trackers (none ran)") : names) +
          " in the colour of the target nearest it (within GOSPA's cut-off c; grey circles: no "
          "target that near: a bird, a ghost, a lost track).",
      [&](GnuplotFigure& figure) { PlotTargetsAndTracks(figure, d); }, warnings);
}

// gospa.csv's `column` per method against time.
Figure GospaTime(const RunData& d, const RunReportOptions& o, std::vector<std::string>* warnings) {
  const std::string png = "report/gospa_time.png";
  const std::string caption =
      "Several targets: GOSPA (p = 2, alpha = 2, cut-off c) of each method's estimates at every "
      "window's end (top), and the parts of the first tracker's (else the first method's): the "
      "localization error of the assigned pairs and c^2/2 per missed target and per false "
      "estimate (bottom; m^2). gospa.csv.";
  if (!d.gospa) return NotDrawn(png, caption, "the run has no gospa.csv", warnings);
  const Table& g = *d.gospa;
  const long t = g.Column("t_s"), m = g.Column("method"), v = g.Column("gospa_m");
  const long parts[] = {g.Column("localization_m2"), g.Column("missed_m2"), g.Column("false_m2")};
  const std::vector<std::string> trackers = Trackers(d);
  const std::string focus = !trackers.empty()   ? trackers.front()
                            : d.methods.empty() ? std::string()
                                                : d.methods.front();
  std::map<std::string, std::string> rows;
  std::string part_rows[3];
  for (std::size_t i = 0; i < g.rows.size(); ++i) {
    const std::string& method = g.rows[i][static_cast<std::size_t>(m)];
    rows[method] += ShortestNumber(g.Number(i, t)) + " " + ShortestNumber(g.Number(i, v)) + "\n";
    if (method == focus)
      for (int p = 0; p < 3; ++p)
        part_rows[p] +=
            ShortestNumber(g.Number(i, t)) + " " + ShortestNumber(g.Number(i, parts[p])) + "\n";
  }
  GnuplotFigure figure;
  std::ostream& gp = figure.Commands();
  gp << "set multiplot\nset lmargin at screen 0.08\nset rmargin at screen 0.80\n"
     << "set tmargin at screen 0.93\nset bmargin at screen 0.55\nset format x ''\nset grid\n"
     << "set title "
     << GnuplotString("GOSPA vs time: " + d.scenario.value("name", std::string("run")))
     << "\nset ylabel 'GOSPA (m)'\nset yrange [0:*]\nset key outside right top\n";
  std::size_t k = 0;
  for (const std::string& method : d.methods) {
    if (!rows.count(method)) continue;
    figure.Data("g" + std::to_string(k), rows[method]);
    figure.Text("uavsim_method" + std::to_string(k), method);
    figure.Curve("$g" + std::to_string(k) + " using 1:2 with lines lw 1.5 lc rgb '" +
                 MethodColour(d, method) + "' title uavsim_method" + std::to_string(k));
    ++k;
  }
  if (!figure.HasCurves()) return NotDrawn(png, caption, "gospa.csv has no rows", warnings);
  figure.Plot(CurveLayout::kOneLine);
  gp << "unset title\nset tmargin at screen 0.50\nset bmargin at screen 0.09\nset format x '%g'\n"
     << "set xlabel 'Simulated time (s)'\nset ylabel " << GnuplotString(focus + ": parts (m^2)")
     << "\n";
  const char* names[] = {"localization", "missed", "false"};
  const char* colours[] = {"#1b9e77", "#d95f02", "#7570b3"};
  for (int p = 0; p < 3; ++p) {
    figure.Data(std::string("part_") + names[p], part_rows[p].empty() ? "NaN NaN\n" : part_rows[p]);
    figure.Curve(std::string("$part_") + names[p] + " using 1:2 with lines lw 1.5 lc rgb '" +
                 colours[p] + "' title '" + names[p] + "'");
  }
  figure.Plot(CurveLayout::kOneLine);
  gp << "unset multiplot\n";
  return Draw(d, o, png, caption, figure, 1100, 620, warnings);
}

// The upper plot: each method's error vs time, on a logarithmic axis when
// the errors span decades.
void PlotErrors(GnuplotFigure& figure, const RunData& d, const Errors& errors) {
  double lo = INFINITY, hi = 0.0;
  for (const auto& [m, rows] : errors.by_method)
    for (const auto& [t, e] : rows)
      if (e > 0) lo = std::min(lo, e), hi = std::max(hi, e);
  const bool log_y = hi > 0 && lo < INFINITY && hi / lo >= 20.0;  // spans decades
  const double t_end = std::max(d.duration_s, d.truth_t.empty() ? 0.0 : d.truth_t.back());
  std::ostream& gp = figure.Commands();
  gp << "set multiplot\n"
     << "set lmargin at screen 0.08\nset rmargin at screen 0.80\n"
     << "set xrange [0:" << ShortestNumber(t_end) << "]\n"
     << "set tmargin at screen 0.93\nset bmargin at screen 0.40\n"
     << "set title "
     << GnuplotString("Localization error vs time: " + d.scenario.value("name", std::string("run")))
     << "\nset ylabel 'Error (m)'\nset format x ''\nset grid\n"
     << "set key outside right top\n"
     << (log_y ? "set logscale y\n" : "set yrange [0:*]\n");
  std::size_t k = 0;
  for (const std::string& method : d.methods) {
    const auto it = errors.by_method.find(method);
    if (it == errors.by_method.end()) continue;
    std::string rows;
    for (const auto& [t, e] : it->second)
      if (!log_y || e > 0) rows += ShortestNumber(t) + " " + ShortestNumber(e) + "\n";
    figure.Data("err" + std::to_string(k), rows);
    figure.Text("uavsim_method" + std::to_string(k), method);
    figure.Curve("$err" + std::to_string(k) + " using 1:2 with lines lw 1.5 lc rgb '" +
                 MethodColour(d, method) + "' title uavsim_method" + std::to_string(k));
    ++k;
  }
  if (!figure.HasCurves())  // a run shorter than every method's warm-up
    gp << "set yrange [0:1]\nset format y ''\nset label 1 'no method produced an estimate' at "
          "graph 0.5, graph 0.5 center\nplot NaN notitle\nunset label 1\nset format y '%g'\n";
  else
    figure.Plot(CurveLayout::kOneLine);
}

// The strip's rows: one per modality, a box per window coloured by state
// (every state in the legend, drawn or not).
void PlotWindowStates(GnuplotFigure& figure, const RunData& d, const Packets& packets) {
  std::ostream& gp = figure.Commands();
  const std::vector<std::string> order = ModalityOrder(packets);
  const std::size_t n = order.size();
  gp << "set yrange [-0.6:" << ShortestNumber(static_cast<double>(n) - 0.4) << "]\nset ytics (";
  for (std::size_t m = 0; m < n; ++m)
    gp << (m ? ", " : "") << GnuplotString(order[m]) << " " << (n - 1 - m);
  gp << ") nomirror\nset style fill solid 1.0 noborder\n";
  const std::pair<const char*, const char*> states[] = {{"on_time", "#1a9641"},
                                                        {"partly", "#a6d96a"},
                                                        {"late", "#fdae61"},
                                                        {"lost", "#d7191c"},
                                                        {"none_sent", "#d9d9d9"}};
  const char* titles[] = {"all on time", "some on time", "none on time (late)",
                          "none arrived (lost)", "nothing sent"};
  std::map<std::string, std::string> rows;
  for (std::size_t w = 0; w < packets.windows.size(); ++w)
    for (std::size_t m = 0; m < n; ++m) {
      const auto it = packets.windows[w].find(order[m]);
      const Reception r = it == packets.windows[w].end() ? Reception{} : it->second;
      rows[WindowState(r)] += ShortestNumber((static_cast<double>(w) + 0.5) * d.window_s) + " " +
                              std::to_string(n - 1 - m) + "\n";
    }
  for (std::size_t s = 0; s < 5; ++s) {
    const std::string name = states[s].first;
    // Every state keeps its legend entry, drawn or not.
    figure.Data("st_" + name, rows.count(name) ? rows[name] : std::string("NaN NaN\n"));
    figure.Curve(std::string("$st_") + name + " using 1:2:(" + ShortestNumber(0.5 * d.window_s) +
                 "):(0.38) with boxxy fc rgb '" + states[s].second + "' title '" + titles[s] + "'");
  }
  figure.Plot(CurveLayout::kOneLine);
}

Figure ErrorTime(const RunData& d, const Errors& errors, const std::optional<Packets>& packets,
                 const RunReportOptions& o, std::vector<std::string>* warnings) {
  const std::string png = "report/error_time.png";
  const std::string caption =
      "Top: each method's error (distance from the truth) at every window's end. Bottom: what the "
      "edge had of each modality in each 0.2 s window: every frame on time, some on time, none "
      "on time (late), none arrived (lost), nothing sent.";
  GnuplotFigure figure;
  PlotErrors(figure, d, errors);
  // The strip: one row per modality, a box per window coloured by state.
  std::ostream& gp = figure.Commands();
  gp << "unset logscale y\nunset title\nset format x '%g'\nset xlabel 'Simulated time (s)'\n"
     << "set tmargin at screen 0.33\nset bmargin at screen 0.09\n"
     << "unset grid\nset ylabel ''\nset key outside right center\n";
  if (!packets) {
    gp << "set yrange [0:1]\nunset ytics\nset label 1 'no packets.csv in this run' at graph 0.5, "
          "graph 0.5 center\n"
       << "plot NaN notitle\n";
  } else {
    PlotWindowStates(figure, d, *packets);
  }
  gp << "unset multiplot\n";
  return Draw(d, o, png, caption, figure, 1100, 620, warnings);
}

Figure PacketsFigure(const RunData& d, const Packets& p, const RunReportOptions& o,
                     std::vector<std::string>* warnings) {
  const std::string png = "report/packets.png";
  const std::string caption =
      "Messages per modality by fate: delivered by its window's deadline, late (arrived after it: "
      "the pipeline treats it as missing), lost on the uplink, still in flight at the end.";
  GnuplotFigure figure;
  // Labels as string expressions, data as numbers only (no name in a block).
  std::string rows, tics;
  const std::vector<std::string> order = ModalityOrder(p);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const Reception& r = p.totals.at(order[k]);
    rows += std::to_string(k) + " " + std::to_string(r.delivered) + " " + std::to_string(r.late) +
            " " + std::to_string(r.lost) + " " + std::to_string(r.in_flight) + "\n";
    tics += (k ? ", " : "") + GnuplotString(order[k]) + " " + std::to_string(k);
  }
  figure.Data("packets", rows);
  figure.Commands()
      << "set title 'Uplink messages by fate'\nset ylabel 'Messages'\n"
      << "set style data histograms\nset style histogram rowstacked\nset boxwidth 0.6\n"
      << "set style fill solid 1.0 border -1\nset yrange [0:*]\nset grid ytics\n"
      << "set key outside right top\nset xtics (" << tics << ")\n";
  figure.Curve("$packets using 2 lc rgb '#1a9641' title 'delivered'");
  figure.Curve("'' using 3 lc rgb '#fdae61' title 'late'");
  figure.Curve("'' using 4 lc rgb '#d7191c' title 'lost'");
  figure.Curve("'' using 5 lc rgb '#969696' title 'in flight'");
  figure.Plot(CurveLayout::kOneLine);
  return Draw(d, o, png, caption, figure, 640, 440, warnings);
}

Figure LatencyFigure(const RunData& d, const Packets& p, CsvTable* csv, const RunReportOptions& o,
                     std::vector<std::string>* warnings) {
  const std::string png = "report/latency.png";
  const std::string caption =
      "Latency (capture to arrival at the edge, on time or late) per modality, as the share of "
      "arrivals within a latency.";
  GnuplotFigure figure;
  std::size_t k = 0;
  const std::vector<std::string> order = ModalityOrder(p);
  for (std::size_t m = 0; m < order.size(); ++m) {
    const auto it = p.latency_ms.find(order[m]);
    if (it == p.latency_ms.end() || it->second.empty()) continue;
    std::vector<double> v = it->second;
    std::sort(v.begin(), v.end());
    std::string rows;
    for (std::size_t i = 0; i < v.size(); ++i) {
      const double f = static_cast<double>(i + 1) / static_cast<double>(v.size());
      rows += ShortestNumber(v[i]) + " " + ShortestNumber(f) + "\n";
      csv->AddRow({order[m], Fixed(v[i], 3), Fixed(f, 6)});
    }
    figure.Data("lat" + std::to_string(k), rows);
    figure.Text("uavsim_mod" + std::to_string(k), order[m]);
    figure.Curve("$lat" + std::to_string(k) + " using 1:2 with steps lw 2 lc rgb '" +
                 ModalityColour(order[m], m) + "' title uavsim_mod" + std::to_string(k));
    ++k;
  }
  if (!figure.HasCurves()) return NotDrawn(png, caption, "no message arrived", warnings);
  figure.Commands()
      << "set title 'Uplink latency (empirical CDF)'\nset xlabel 'Latency (ms)'\n"
      << "set ylabel 'Share of arrivals'\nset yrange [0:1.02]\nset grid\nset key right bottom\n";
  figure.Plot(CurveLayout::kOneLine);
  return Draw(d, o, png, caption, figure, 640, 440, warnings);
}

// rate_snr.png from rate_snr.csv (every window; a method without an
// estimate yet scores gain 0) or, `common`, rate_snr_common.png from
// rate_snr_common.csv (the windows every steering method estimated).
Figure DrawRates(const RunData& d, const RunReportOptions& o, const std::string& png,
                 const std::string& caption, const std::string& title, const std::string& y_label,
                 const std::vector<std::string>& beams, std::map<std::string, std::string>& rows,
                 std::vector<std::string>* warnings);

Figure RateSnr(const RunData& d, bool common, const RunReportOptions& o,
               std::vector<std::string>* warnings) {
  const std::string stem = common ? "rate_snr_common" : "rate_snr";
  const std::string png = stem + ".png";
  const std::string caption =
      common ? "The same over the " +
                   JsonText(d.metrics.value("rate_snr_common_windows", Json(nullptr))) +
                   " windows in which every method that steers a beam had an estimate: the "
                   "methods compared on the same windows."
             : "Achievable downlink rate vs SNR with the base station's beam steered at the truth "
               "(perfect) and at each method's estimate, over every window (a method scores gain "
               "0 before its first estimate).";
  const std::optional<Table>& table = common ? d.rate_snr_common : d.rate_snr;
  if (!table) return NotDrawn(png, caption, "the run has no " + stem + ".csv", warnings);
  const Table& t = *table;
  const long sc = t.Column("snr_db"), bc = t.Column("beam"), rc = t.Column("rate_bps_hz");
  std::vector<std::string> beams;
  std::map<std::string, std::string> rows;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const std::string& beam = t.rows[i][static_cast<std::size_t>(bc)];
    if (!rows.count(beam)) beams.push_back(beam);
    rows[beam] += ShortestNumber(t.Number(i, sc)) + " " + ShortestNumber(t.Number(i, rc)) + "\n";
  }
  // No common window (a short run, a method that never answered) is an
  // outcome, not a fault: said on the page, no warning.
  if (beams.empty() && common)
    return {png, caption, "no window in which every method that steers a beam had an estimate"};
  if (beams.empty()) return NotDrawn(png, caption, stem + ".csv has no rows", warnings);
  return DrawRates(d, o, png, caption,
                   std::string(common ? "On common windows: " : "Achievable rate vs SNR: "),
                   "Rate (bit/s/Hz)", beams, rows, warnings);
}

// Sum rate vs SNR (rate_snr_targets.csv's "sum" rows), a curve per beam set.
Figure SumRateSnr(const RunData& d, const RunReportOptions& o, std::vector<std::string>* warnings) {
  const std::string png = "rate_snr_targets.png";
  const std::string caption =
      "Several targets: the sum over the targets of each one's achievable rate vs SNR, the base "
      "station pointing a beam at every estimate a method has (equal power each; each target "
      "served by the beam assigned to it, the others' leakage as interference) and, as the "
      "reference, at every target's true position (perfect). Per target: rate_snr_targets.csv.";
  if (!d.rate_snr_targets)
    return NotDrawn(png, caption, "the run has no rate_snr_targets.csv", warnings);
  const Table& t = *d.rate_snr_targets;
  const long sc = t.Column("snr_db"), bc = t.Column("beam"), tc = t.Column("target"),
             rc = t.Column("rate_bps_hz");
  std::vector<std::string> beams;
  std::map<std::string, std::string> rows;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    if (t.rows[i][static_cast<std::size_t>(tc)] != "sum") continue;
    const std::string& beam = t.rows[i][static_cast<std::size_t>(bc)];
    if (!rows.count(beam)) beams.push_back(beam);
    rows[beam] += ShortestNumber(t.Number(i, sc)) + " " + ShortestNumber(t.Number(i, rc)) + "\n";
  }
  if (beams.empty()) return NotDrawn(png, caption, "rate_snr_targets.csv has no rows", warnings);
  return DrawRates(d, o, png, caption, "Sum rate vs SNR: ", "Sum rate (bit/s/Hz)", beams, rows,
                   warnings);
}

Figure DrawRates(const RunData& d, const RunReportOptions& o, const std::string& png,
                 const std::string& caption, const std::string& title, const std::string& y_label,
                 const std::vector<std::string>& beams, std::map<std::string, std::string>& rows,
                 std::vector<std::string>* warnings) {
  GnuplotFigure figure;
  for (std::size_t k = 0; k < beams.size(); ++k) {
    figure.Data("b" + std::to_string(k), rows[beams[k]]);
    figure.Text("uavsim_beam" + std::to_string(k), beams[k]);
    const bool method = std::find(d.methods.begin(), d.methods.end(), beams[k]) != d.methods.end();
    const std::string colour = beams[k] == "perfect" ? "black"
                               : method              ? MethodColour(d, beams[k])
                                                     : "#777777";
    figure.Curve("$b" + std::to_string(k) +
                 " using 1:2 with linespoints pt 7 ps 0.6 lw 1.5 lc rgb '" + colour +
                 "' title uavsim_beam" + std::to_string(k));
  }
  figure.Commands() << "set title "
                    << GnuplotString(title + d.scenario.value("name", std::string("run")))
                    << "\nset xlabel 'SNR (dB)'\nset ylabel " << GnuplotString(y_label)
                    << "\nset grid\nset key top left\n";
  figure.Plot(CurveLayout::kOneLine);
  return Draw(d, o, png, caption, figure, 800, 560, warnings);
}

// ---------------------------------------------------------------------------
// The page's tables

// metrics.json's gospa: a row per method.
std::vector<std::vector<std::string>> GospaRows(const RunData& d) {
  std::vector<std::vector<std::string>> rows{
      {"method", "GOSPA RMS (m)", "OSPA RMS (m)", "missed / window", "false / window",
       "cardinality error", "identity switches", "fragmentations"}};
  const Json methods = At(d.metrics, "/gospa/methods");
  if (!methods.is_object()) return {};
  for (const auto& [method, g] : methods.items())
    rows.push_back({method, JsonFixed(g, "rms_m", 2), JsonFixed(g, "ospa_rms_m", 2),
                    JsonFixed(g, "missed_per_window", 2), JsonFixed(g, "false_per_window", 2),
                    JsonFixed(g, "cardinality_error", 2),
                    JsonText(g.value("identity_switches", Json(nullptr))),
                    JsonText(g.value("fragmentations", Json(nullptr)))});
  return rows;
}

std::vector<std::vector<std::string>> RmseRows(const RunData& d, const Errors& errors) {
  std::vector<std::vector<std::string>> rows{{"method", "RMSE (m)", "windows estimated",
                                              "RMSE on common windows (m)", "median error (m)",
                                              "90th percentile (m)"}};
  const Json rmse = d.metrics.value("rmse_m", Json::object());
  const Json windows = d.metrics.value("estimated_windows", Json::object());
  const Json common = d.metrics.value("rmse_common_m", Json::object());
  for (const std::string& m : d.methods) {
    std::vector<double> e;
    if (const auto it = errors.by_method.find(m); it != errors.by_method.end())
      for (const auto& [t, x] : it->second) e.push_back(x);
    rows.push_back({m, JsonFixed(rmse, m, 3), windows.contains(m) ? JsonText(windows.at(m)) : "-",
                    JsonFixed(common, m, 3), e.empty() ? "-" : Fixed(Quantile(e, 0.5), 3),
                    e.empty() ? "-" : Fixed(Quantile(e, 0.9), 3)});
  }
  return rows;
}

std::vector<std::vector<std::string>> ReceptionRows(const RunData& d) {
  std::vector<std::vector<std::string>> rows{{"modality", "frames", "sent", "delivered", "late",
                                              "lost", "in flight", "latency mean (ms)", "p50 (ms)",
                                              "p95 (ms)", "p99 (ms)"}};
  const Json mods = d.metrics.value("modalities", Json::object());
  for (const auto& [m, v] : mods.items()) {
    const Json lat = v.value("latency_s", Json(nullptr));
    const auto ms = [&lat](const char* key) {
      return lat.is_object() && lat.contains(key) && lat.at(key).is_number()
                 ? Fixed(1000.0 * lat.at(key).get<double>(), 2)
                 : std::string("-");
    };
    const auto count = [&v](const char* key) {
      return v.contains(key) ? JsonText(v.at(key)) : "-";
    };
    rows.push_back({m, count("frames"), count("packets_sent"), count("packets_delivered"),
                    count("packets_late"), count("packets_lost"), count("packets_in_flight"),
                    ms("mean"), ms("p50"), ms("p95"), ms("p99")});
  }
  return rows;
}

std::vector<std::vector<std::string>> DataRateRows(const RunData& d) {
  std::vector<std::vector<std::string>> rows{
      {"modality", "raw (kB/s)", "pre-processed (kB/s)", "compressed (kB/s)", "raw / compressed"}};
  const Json rates = d.metrics.value("data_rate_kBps", Json::object());
  for (const auto& [m, v] : rates.items()) {
    const double raw = v.value("raw", 0.0), compressed = v.value("compressed", 0.0);
    rows.push_back({m, JsonFixed(v, "raw", 1), JsonFixed(v, "preprocessed", 2),
                    JsonFixed(v, "compressed", 3),
                    compressed > 0 ? Fixed(raw / compressed, 0) + "x" : std::string("-")});
  }
  return rows;
}

// A /pipeline/methods entry as the report's table names it: "ekf", "mine
// (TorchScript mine.pt)", "mine (Python, 10 windows)".
std::string MethodLabel(const Json& x) {
  if (!x.is_object()) return JsonText(x);
  const std::string name = JsonText(x.value("name", Json(nullptr)));
  if (x.value("type", std::string("torchscript")) == "python")
    return name + " (Python, " + JsonText(x.value("history_windows", Json(1))) + " windows)";
  return name + " (TorchScript " + JsonText(x.value("edge", Json(nullptr))) + ")";
}

std::vector<std::vector<std::string>> SettingsRows(const RunData& d) {
  const Json& s = d.scenario;
  std::vector<std::vector<std::string>> rows{{"setting", "value"}};
  const auto add = [&rows](const std::string& name, const std::string& value) {
    rows.push_back({name, value});
  };
  add("scenario file", JsonText(d.manifest.value("scenario_file", Json(nullptr))));
  add("seed", JsonText(d.manifest.value("seed", Json(nullptr))));
  add("duration (s)", JsonText(At(s, "/duration_s")));
  add("city", JsonText(At(s, "/world/city/type")));
  std::string weather = "rain " + JsonText(At(s, "/weather/rain_mm_h")) + " mm/h, fog visibility " +
                        JsonText(At(s, "/weather/fog_visibility_m")) +
                        (At(s, "/weather/fog_visibility_m").is_null() ? "" : " m") +
                        ", illumination " + JsonText(At(s, "/weather/illumination"));
  add("weather", weather);
  add("birds", JsonText(At(s, "/distractors/birds")));
  if (const Json uavs = At(s, "/uavs"); uavs.is_array())
    for (std::size_t i = 0; i < uavs.size(); ++i)
      add("UAV " + JsonText(uavs[i].value("id", Json(std::to_string(i)))),
          "trajectory " + JsonText(At(uavs[i], "/trajectory/type")));
  if (const Json nodes = At(s, "/nodes"); nodes.is_array())
    for (const Json& n : nodes) {
      const Json p = At(n, "/sensor/pose/position_m");
      std::string where =
          p.is_array() && p.size() == 3
              ? " at (" + JsonText(p[0]) + ", " + JsonText(p[1]) + ", " + JsonText(p[2]) + ") m"
              : "";
      add("node " + JsonText(n.value("id", Json("?"))),
          JsonText(At(n, "/sensor/type")) + ", " + JsonText(At(n, "/sensor/rate_hz")) + " Hz" +
              where + ", uplink " + JsonText(n.value("uplink", Json("?"))));
    }
  if (const Json links = At(s, "/links"); links.is_object())
    for (const auto& [name, l] : links.items()) {
      std::string loss = JsonText(At(l, "/loss/type"));
      if (At(l, "/loss/p").is_number()) loss += " p = " + JsonText(At(l, "/loss/p"));
      add("link " + name, JsonText(At(l, "/bandwidth_mbps")) + " Mbit/s, latency " +
                              JsonText(At(l, "/latency_ms")) + " ms, jitter " +
                              JsonText(At(l, "/jitter/type")) + ", loss " + loss);
    }
  add("base station", "UPA " + JsonText(At(s, "/base_station/upa/mx")) + "x" +
                          JsonText(At(s, "/base_station/upa/my")) + " at " +
                          JsonText(At(s, "/base_station/carrier_ghz")) + " GHz, path model " +
                          JsonText(At(s, "/base_station/path_model")));
  std::string methods;
  if (const Json m = At(s, "/pipeline/methods"); m.is_array())
    for (const Json& x : m) methods += (methods.empty() ? "" : ", ") + MethodLabel(x);
  add("methods", methods);
  add("model", JsonText(At(s, "/pipeline/model")));
  add("window (s)", JsonText(At(s, "/pipeline/window_s")));
  add("uavsim", JsonText(d.manifest.value("uavsim_version", Json(nullptr))) + " (" +
                    JsonText(d.manifest.value("git_hash", Json(nullptr))) + "), started " +
                    JsonText(d.manifest.value("started_utc", Json(nullptr))));
  return rows;
}

std::vector<std::vector<std::string>> ProfileRows(const RunData& d) {
  std::vector<std::vector<std::string>> rows{{"part", "wall (s)", "share of the run's wall time"}};
  const Json profile = d.metrics.value("profile_s", Json::object());
  const double wall = d.metrics.value("wall_s", 0.0);
  std::vector<std::pair<double, std::string>> parts;
  for (const auto& [part, v] : profile.items())
    if (v.is_number()) parts.emplace_back(v.get<double>(), part);
  std::stable_sort(parts.begin(), parts.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [seconds, part] : parts)
    rows.push_back(
        {part, Fixed(seconds, 2), wall > 0 ? Fixed(100.0 * seconds / wall, 1) + " %" : "-"});
  return rows;
}

void AddFigure(HtmlPage& page, const Figure& f) { page.Figure(f.png, f.caption, f.missing); }

// Per alignment window and modality, its messages by fate and the state.
CsvTable WindowsTable(const RunData& d, const Packets& packets) {
  CsvTable windows({"window", "t_start_s", "t_end_s", "modality", "sent", "delivered", "late",
                    "lost", "in_flight", "state"});
  const std::vector<std::string> order = ModalityOrder(packets);
  for (std::size_t w = 0; w < packets.windows.size(); ++w)
    for (const std::string& m : order) {
      const auto it = packets.windows[w].find(m);
      const Reception r = it == packets.windows[w].end() ? Reception{} : it->second;
      windows.AddRow({std::to_string(w), Fixed(static_cast<double>(w) * d.window_s, 6),
                      Fixed(static_cast<double>(w + 1) * d.window_s, 6), m,
                      std::to_string(r.sent()), std::to_string(r.delivered), std::to_string(r.late),
                      std::to_string(r.lost), std::to_string(r.in_flight), WindowState(r)});
    }
  return windows;
}

// Per modality, its messages by fate over the run.
CsvTable TotalsTable(const Packets& packets) {
  CsvTable totals({"modality", "delivered", "late", "lost", "in_flight"});
  for (const std::string& m : ModalityOrder(packets)) {
    const Reception& r = packets.totals.at(m);
    totals.AddRow({m, std::to_string(r.delivered), std::to_string(r.late), std::to_string(r.lost),
                   std::to_string(r.in_flight)});
  }
  return totals;
}

// The reception tables under report/ and their figures (or, without
// packets.csv, the note that they are missing).
std::vector<Figure> WriteReception(const RunData& d, const std::optional<Packets>& packets,
                                   const fs::path& report, const RunReportOptions& options,
                                   std::vector<std::string>* warnings) {
  std::vector<Figure> reception;
  if (!packets) {
    reception.push_back(NotDrawn("report/packets.png", "Messages per modality by fate.",
                                 "the run has no packets.csv (made by an older uavsim)", warnings));
    return reception;
  }
  core::WriteFileAtomic((report / "windows.csv").string(), WindowsTable(d, *packets).str());
  core::WriteFileAtomic((report / "packets_by_fate.csv").string(), TotalsTable(*packets).str());
  CsvTable latency_csv({"modality", "latency_ms", "fraction"});
  reception.push_back(PacketsFigure(d, *packets, options, warnings));
  reception.push_back(LatencyFigure(d, *packets, &latency_csv, options, warnings));
  core::WriteFileAtomic((report / "latency.csv").string(), latency_csv.str());
  return reception;
}

struct ReportFigures {
  std::vector<Figure> reception;
  Figure top, error_time, rate, rate_common;
  std::optional<Figure> targets_top, gospa_time, sum_rate;  // several targets, or mtt
};

std::string Headline(const RunData& d) {
  return "Simulated " + JsonFixed(d.metrics, "sim_s", 1) + " s in " +
         JsonFixed(d.metrics, "wall_s", 1) + " s of wall time (" +
         JsonFixed(d.metrics, "realtime_factor", 2) + "x real time); " +
         JsonText(d.metrics.value("windows", Json(nullptr))) + " alignment windows of " +
         ShortestNumber(d.window_s) + " s.";
}

// Links to the run's files and the report's tables that exist.
std::string FileLinks(const RunData& d) {
  std::error_code ec;
  std::string links;
  for (const char* f : {"manifest.json", "metrics.json", "truth.csv", "estimates.csv",
                        "packets.csv", "rate_snr.csv", "rate_snr_common.csv", "gospa.csv",
                        "rate_snr_targets.csv", "world_top.csv", "layout.csv", "report/errors.csv",
                        "report/windows.csv", "report/packets_by_fate.csv", "report/latency.csv"}) {
    if (!fs::is_regular_file(d.dir / f, ec)) continue;
    links += std::string(links.empty() ? "" : " · ") + "<a href=\"" + HtmlEscape(f) + "\">" +
             HtmlEscape(f) + "</a>";
  }
  return links;
}

// report.html: the tables and figures, section by section.
std::string RunPage(const RunData& d, const Errors& errors, const ReportFigures& figures) {
  const std::string name = d.scenario.value("name", std::string("run"));
  HtmlPage page("uavsim run: " + name);
  page.Paragraph(Headline(d));
  page.Heading("Localization");
  page.Table(RmseRows(d, errors));
  page.Paragraph(
      "RMSE over the windows each method estimated; the common windows are those every method "
      "estimated (methods start at different windows). Median and 90th percentile of the same "
      "errors (report/errors.csv).");
  AddFigure(page, figures.top);
  AddFigure(page, figures.error_time);
  if (const auto rows = GospaRows(d); !rows.empty()) {
    page.Heading("Several targets");
    page.Table(rows);
    page.Paragraph(
        "GOSPA (p = 2, alpha = 2, cut-off c = " + JsonFixed(At(d.metrics, "/gospa"), "c_m", 1) +
        " m) of each method's estimates as a set against every target, per window, RMS over the "
        "windows; OSPA likewise; the missed targets and false estimates per window; the mean "
        "|estimates - targets|; a target's identity switch is an assignment to another track "
        "label than its last, a fragmentation an assignment after windows without one. Per "
        "target RMSE in metrics.json (gospa.methods.<method>.per_target).");
    if (figures.targets_top) AddFigure(page, *figures.targets_top);
    if (figures.gospa_time) AddFigure(page, *figures.gospa_time);
    if (figures.sum_rate) AddFigure(page, *figures.sum_rate);
  }
  page.Heading("Uplink: what reached the edge");
  page.Table(ReceptionRows(d));
  page.BeginRow();
  for (const Figure& f : figures.reception) AddFigure(page, f);
  page.EndRow();
  page.Heading("Data rates (as the paper's Table II)");
  page.Table(DataRateRows(d));
  page.Paragraph(
      "Raw: the sensor's frames; pre-processed: what the node's pre-processing keeps; compressed: "
      "the IB-CC latent messages sent on the uplink.");
  page.Heading("Base-station beam");
  page.BeginRow();
  AddFigure(page, figures.rate);
  AddFigure(page, figures.rate_common);
  page.EndRow();
  page.Heading("Scenario");
  page.Table(SettingsRows(d));
  page.Heading("Where the wall time went");
  page.Table(ProfileRows(d));
  page.Paragraph(
      "Wall seconds per part (metrics.json profile_s). Nodes that capture on threads of their own "
      "overlap the rest, so the parts can sum to more than the run's wall time.");
  page.Heading("Files");
  page.RawParagraph(FileLinks(d));
  return page.str();
}

}  // namespace

std::vector<std::string> WriteRunReport(const std::string& dir, const RunReportOptions& options) {
  const RunData d = Load(dir);
  std::vector<std::string> warnings;
  const Errors errors = ComputeErrors(d);
  std::optional<Packets> packets;
  if (d.packets) packets = CountPackets(d);

  const fs::path report = d.dir / "report";
  std::error_code ec;
  fs::create_directories(report, ec);
  if (ec) throw std::runtime_error(report.string() + ": cannot create folder: " + ec.message());
  core::WriteFileAtomic((report / "errors.csv").string(), errors.csv.str());

  ReportFigures figures;
  figures.reception = WriteReception(d, packets, report, options, &warnings);
  figures.top = TopView(d, options, &warnings);
  figures.error_time = ErrorTime(d, errors, packets, options, &warnings);
  figures.rate = RateSnr(d, false, options, &warnings);
  figures.rate_common = RateSnr(d, true, options, &warnings);
  if (d.gospa) {
    if (d.targets.size() > 1) figures.targets_top = TargetsTopView(d, options, &warnings);
    figures.gospa_time = GospaTime(d, options, &warnings);
    if (d.rate_snr_targets) figures.sum_rate = SumRateSnr(d, options, &warnings);
  }
  core::WriteFileAtomic((d.dir / "report.html").string(), RunPage(d, errors, figures));
  return warnings;
}

}  // namespace uavsim::results
