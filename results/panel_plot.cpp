// Small multiples with gnuplot's multiplot: every panel placed by screen
// margins (so all plot areas have the same size whatever their tic labels),
// the shared ranges worked out here from all the data, the legend drawn by
// one more "plot" of undefined curves into a strip below the panels.
#include "results/panel_plot.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "results/csv.h"
#include "results/figure_style.h"
#include "results/gnuplot.h"

namespace uavsim::results {
namespace {

namespace fs = std::filesystem;

constexpr int kMaxImagePx = 8192;

// Pixels of one panel's cell around its plot area, and of the figure.
constexpr int kGutterPx = 26;     // left of the first column: its y label
constexpr int kLeftPx = 58;       // y tic labels
constexpr int kRightPx = 18;      // the last x tic label's overhang
constexpr int kTopPx = 34;        // the panel's title
constexpr int kBottomPx = 50;     // x tic labels and the x label
constexpr int kEdgePx = 10;       // right of the last column
constexpr int kTitleLinePx = 22;  // a line of the figure's title (sans 14)
constexpr int kPanelLinePx = 18;  // a line of a panel's title (sans 12)
constexpr int kCharPx = 8;        // a character of the legend or a panel title, roughly
constexpr int kTitleCharPx = 9;   // a character of the figure title, roughly
constexpr int kKeyRowPx = 22;     // a row of the legend

// Colours (results/figure_style.h) and filled point shapes, cycled; after
// ten series the lines turn dashed, so that no two series look alike up to 30.
constexpr int kPointTypes[] = {7, 5, 9, 11, 13, 15};

struct Point {
  double x = 0.0, y = 0.0;
  double ci = -1.0;  // < 0: no band
};

struct Panel {
  std::string name;
  std::vector<std::vector<Point>> series;  // by series index
};

// The line and points of series number `series`; with many points, a
// marker on every `interval`-th only.
std::string Style(std::size_t series, std::size_t interval = 1) {
  std::string s = "lc rgb '" + std::string(kSeriesColours[series % kSeriesColourCount]) +
                  "' lw 2 pt " + std::to_string(kPointTypes[series % 6]) + " ps 1.1";
  if (interval > 1) s += " pi " + std::to_string(interval);
  if (series >= 10) s += " dt " + std::to_string(1 + static_cast<int>(series / 10));
  return s;
}

// The pixel offsets as a screen coordinate ("at screen f").
struct Canvas {
  int width = 0, height = 0;
  std::string X(int px) const { return ShortestNumber(static_cast<double>(px) / width); }
  std::string Y(int px_from_top) const {
    return ShortestNumber(1.0 - static_cast<double>(px_from_top) / height);
  }
};

struct Range {
  double lo = 0.0, hi = 0.0;
};

// A range around [lo, hi] with a margin, so no point sits on the border.
Range Padded(double lo, double hi, bool log, double fraction) {
  if (log) {
    const double f = hi > lo ? std::pow(hi / lo, fraction) : 1.5;
    return {lo / f, hi * f};
  }
  const double pad = hi > lo ? fraction * (hi - lo) : (lo != 0.0 ? 0.1 * std::abs(lo) : 1.0);
  return {lo - pad, hi + pad};
}

}  // namespace

PanelGrid ChoosePanelGrid(int panels, int max_columns) {
  if (panels <= 0) return {};
  const int most = std::max(1, max_columns);
  const int rows = (panels + most - 1) / most;
  return {(panels + rows - 1) / rows, rows};
}

std::string PlotPanels(const std::string& csv_path, const PanelPlotSpec& spec) {
  const std::string where = "panel plot " + csv_path + ": ";
  if (spec.panel_width_px < 160 || spec.panel_height_px < 120 || spec.max_columns < 1)
    return where + "panels must be at least 160 x 120 pixels, and at least one per row";
  const std::string png =
      spec.png_path.empty() ? fs::path(csv_path).replace_extension(".png").string() : spec.png_path;

  // ---- Read and check the CSV.
  CsvFile csv;
  if (std::string err = ReadCsvFile(csv_path, &csv); !err.empty()) return where + err;
  long col[5];
  const char* names[5] = {"x", "y", "ci95", "series", "panel"};
  for (int k = 0; k < 5; ++k) {
    col[k] = csv.Column(names[k]);
    if (col[k] < 0) return where + "no column \"" + names[k] + "\"";
  }

  std::vector<std::string> series_names;
  std::vector<Panel> panels;
  std::size_t drawn = 0;
  for (std::size_t r = 0; r < csv.rows.size(); ++r) {
    const std::vector<std::string>& cells = csv.rows[r];
    const std::string at = where + "line " + std::to_string(csv.line[r]) + ": ";
    Point p;
    const std::string &x_cell = cells[col[0]], &y_cell = cells[col[1]], &ci_cell = cells[col[2]];
    if (!ParseFiniteNumber(x_cell, &p.x)) return at + "expected a finite number in \"x\"";
    if (!y_cell.empty() && !ParseFiniteNumber(y_cell, &p.y))
      return at + "expected an empty cell or a finite number in \"y\"";
    if (!ci_cell.empty() && (!ParseFiniteNumber(ci_cell, &p.ci) || p.ci < 0.0))
      return at + "expected an empty cell or a finite number >= 0 in \"ci95\"";
    if (spec.log_x && p.x <= 0.0) return at + "x must be > 0 on a logarithmic axis";
    if (spec.log_y && !y_cell.empty() && p.y <= 0.0)
      return at + "y must be > 0 on a logarithmic axis";

    const std::string& panel_name = cells[col[4]];
    auto panel = std::find_if(panels.begin(), panels.end(),
                              [&](const Panel& q) { return q.name == panel_name; });
    if (panel == panels.end()) {
      panels.push_back({panel_name, {}});
      panel = panels.end() - 1;
    }
    if (y_cell.empty()) continue;  // a missing point
    const std::string& series_name = cells[col[3]];
    const auto s = static_cast<std::size_t>(
        std::find(series_names.begin(), series_names.end(), series_name) - series_names.begin());
    if (s == series_names.size()) series_names.push_back(series_name);
    if (panel->series.size() <= s) panel->series.resize(s + 1);
    panel->series[s].push_back(p);
    ++drawn;
  }
  if (drawn == 0) return where + "no data rows";

  // ---- Shared ranges over every panel.
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo;
  double y_lo = x_lo, y_hi = -x_lo;        // the points
  double band_lo = x_lo, band_hi = -x_lo;  // the points and their bands
  bool any_band = false;
  for (auto& panel : panels)
    for (auto& points : panel.series) {
      std::stable_sort(points.begin(), points.end(),
                       [](const Point& a, const Point& b) { return a.x < b.x; });
      for (const Point& p : points) {
        x_lo = std::min(x_lo, p.x), x_hi = std::max(x_hi, p.x);
        y_lo = std::min(y_lo, p.y), y_hi = std::max(y_hi, p.y);
        const double ci = std::max(p.ci, 0.0);
        any_band = any_band || p.ci > 0.0;
        if (!spec.log_y || p.y - ci > 0.0) band_lo = std::min(band_lo, p.y - ci);
        band_hi = std::max(band_hi, p.y + ci);
      }
    }
  const Range xr = Padded(x_lo, x_hi, spec.log_x, 0.04);
  double top = band_hi, bottom = std::min(band_lo, y_lo);
  if (std::isfinite(spec.y_max)) top = std::max(std::min(top, spec.y_max), y_hi);
  const bool from_zero = spec.y_min_zero && !spec.log_y;
  if (from_zero) bottom = std::min(0.0, y_lo);
  Range yr = Padded(bottom, top, spec.log_y, 0.05);
  if (from_zero && bottom == 0.0) yr.lo = 0.0;
  // A capped axis ends at its cap when the data reach it.
  if (std::isfinite(spec.y_max) && top == spec.y_max) yr.hi = spec.y_max + 0.02 * (top - yr.lo);

  // ---- Layout.
  const int n = static_cast<int>(panels.size());
  const PanelGrid grid = ChoosePanelGrid(n, spec.max_columns);
  const std::size_t entries = series_names.size() + (any_band ? 1 : 0);
  int longest = Utf8Chars(any_band ? spec.band_label : std::string());
  for (const auto& s : series_names) longest = std::max(longest, Utf8Chars(s));
  Canvas canvas;
  canvas.width = kGutterPx + grid.columns * spec.panel_width_px + kEdgePx;
  const int entry_px = kCharPx * longest + 70;
  const int per_row = std::clamp((canvas.width - 40) / entry_px, 1, static_cast<int>(entries));
  const int key_rows = (static_cast<int>(entries) + per_row - 1) / per_row;
  const int key_px = 18 + (spec.legend_title.empty() ? 0 : kKeyRowPx) + key_rows * kKeyRowPx;
  // Titles wrapped to their width: the figure's above the panels, each
  // panel's above its plot area (all panels as tall as the tallest needs).
  const std::vector<std::string> title_lines =
      WrapWords(spec.title, (canvas.width - 24) / kTitleCharPx);
  const int title_px =
      12 + static_cast<int>(title_lines.size()) * kTitleLinePx + (title_lines.empty() ? 0 : 10);
  std::vector<std::vector<std::string>> panel_lines;
  std::size_t most_panel_lines = 1;
  for (const auto& panel : panels) {
    panel_lines.push_back(WrapWords(panel.name, (spec.panel_width_px - 16) / kCharPx));
    most_panel_lines = std::max(most_panel_lines, panel_lines.back().size());
  }
  const int top_px = kTopPx + kPanelLinePx * static_cast<int>(most_panel_lines - 1);
  canvas.height = title_px + grid.rows * spec.panel_height_px + key_px;
  if (canvas.width > kMaxImagePx || canvas.height > kMaxImagePx)
    return where + std::to_string(n) + " panels need a " + std::to_string(canvas.width) + " x " +
           std::to_string(canvas.height) + " image; the limit is " + std::to_string(kMaxImagePx) +
           " pixels";

  // ---- The script. Texts through variables: `title` and `set title` take
  // string expressions there.
  std::ostringstream gp;
  gp << "uavsim_title = " << GnuplotLines(title_lines) << "\n"
     << "uavsim_xlabel = " << GnuplotString(spec.x_label) << "\n"
     << "uavsim_ylabel = " << GnuplotString(spec.y_label) << "\n"
     << "uavsim_key = " << GnuplotString(spec.legend_title) << "\n"
     << "uavsim_band = " << GnuplotString(spec.band_label) << "\n";
  for (std::size_t s = 0; s < series_names.size(); ++s)
    gp << "uavsim_series" << s << " = " << GnuplotString(series_names[s]) << "\n";
  for (int k = 0; k < n; ++k)
    gp << "uavsim_panel" << k << " = " << GnuplotLines(panel_lines[k]) << "\n";
  gp << "set datafile separator whitespace\n";
  // Per panel and series: x, y, band bottom, band top (the bottom raised to
  // the axis on a logarithmic axis, where y - ci95 may be <= 0).
  for (int k = 0; k < n; ++k)
    for (std::size_t s = 0; s < panels[k].series.size(); ++s) {
      if (panels[k].series[s].empty()) continue;
      gp << "$p" << k << "s" << s << " << EOD\n";
      for (const Point& p : panels[k].series[s]) {
        const double ci = std::max(p.ci, 0.0);
        const double low = spec.log_y && p.y - ci <= yr.lo ? yr.lo : p.y - ci;
        gp << ShortestNumber(p.x) << " " << ShortestNumber(p.y) << " " << ShortestNumber(low) << " "
           << ShortestNumber(p.y + ci) << "\n";
      }
      gp << "EOD\n";
    }
  gp << "set multiplot" << (spec.title.empty() ? "" : " title uavsim_title font ',14'") << "\n"
     << "unset key\n"
     << "set grid lt 1 lc rgb '#e3e3e3' lw 1\n"
     << "set tics out nomirror\n"
     << "set border 3 lc rgb '#444444'\n"
     << "set style fill transparent solid 0.2 noborder\n";
  if (spec.log_x) gp << "set logscale x\n";
  if (spec.log_y) gp << "set logscale y\n";
  gp << "set xrange [" << ShortestNumber(xr.lo) << ":" << ShortestNumber(xr.hi) << "]\n"
     << "set yrange [" << ShortestNumber(yr.lo) << ":" << ShortestNumber(yr.hi) << "]\n";
  for (int k = 0; k < n; ++k) {
    const int r = k / grid.columns, c = k % grid.columns;
    const int x0 = kGutterPx + c * spec.panel_width_px, y0 = title_px + r * spec.panel_height_px;
    gp << "set lmargin at screen " << canvas.X(x0 + kLeftPx) << "\n"
       << "set rmargin at screen " << canvas.X(x0 + spec.panel_width_px - kRightPx) << "\n"
       << "set tmargin at screen " << canvas.Y(y0 + top_px) << "\n"
       << "set bmargin at screen " << canvas.Y(y0 + spec.panel_height_px - kBottomPx) << "\n"
       << "set title uavsim_panel" << k
       << " font ',12'\n"
       // The x label under each column's lowest panel, the y label left of
       // each row.
       << (k + grid.columns >= n ? "set xlabel uavsim_xlabel\n" : "unset xlabel\n")
       << (c == 0 ? "set ylabel uavsim_ylabel\n" : "unset ylabel\n");
    std::vector<std::string> bands, lines;
    const auto& series = panels[k].series;
    for (std::size_t s = 0; s < series.size(); ++s) {
      if (series[s].empty()) continue;
      const std::string data = "$p" + std::to_string(k) + "s" + std::to_string(s);
      const bool band =
          std::any_of(series[s].begin(), series[s].end(), [](const Point& p) { return p.ci > 0; });
      if (band)
        bands.push_back(data + " using 1:3:4 with filledcurves fc rgb '" +
                        kSeriesColours[s % kSeriesColourCount] + "' notitle");
      // Markers name the series; beyond 8 a line, every few suffice.
      const std::size_t interval = (series[s].size() + 7) / 8;
      lines.push_back(data + " using 1:2 with linespoints " + Style(s, interval) + " notitle");
    }
    if (lines.empty()) {
      gp << "set label 1 'no values' at graph 0.5, 0.5 center tc rgb '#888888'\n"
         << "plot NaN notitle\nunset label 1\n";
      continue;
    }
    // Bands first, so that no band veils another series' line.
    bands.insert(bands.end(), lines.begin(), lines.end());
    gp << "plot ";
    for (std::size_t i = 0; i < bands.size(); ++i) gp << (i ? ", \\\n     " : "") << bands[i];
    gp << "\n";
  }

  // The legend: undefined curves in the strip below the panels.
  gp << "set lmargin at screen 0\nset rmargin at screen 1\n"
     << "set tmargin at screen " << canvas.Y(title_px + grid.rows * spec.panel_height_px + 4)
     << "\nset bmargin at screen 0\n"
     << "unset title\nunset xlabel\nunset ylabel\nunset logscale\nunset grid\nunset border\n"
     << "unset tics\nset xrange [0:1]\nset yrange [0:1]\n"
     << "set key center center horizontal Left reverse samplen 3 spacing 1.1 width 1 maxcols "
     << per_row << (spec.legend_title.empty() ? "" : " title uavsim_key") << "\n"
     << "plot ";
  for (std::size_t s = 0; s < series_names.size(); ++s)
    gp << (s ? ", \\\n     " : "") << "NaN with linespoints " << Style(s) << " title uavsim_series"
       << s;
  if (any_band)
    gp << ", \\\n     NaN with filledcurves fc rgb '#555555' fs transparent solid 0.25 "
          "title uavsim_band";
  gp << "\nunset multiplot\n";

  GnuplotImage image;
  image.png_path = png;
  image.width_px = canvas.width;
  image.height_px = canvas.height;
  image.font = "sans,11";
  image.gnuplot = spec.gnuplot;
  if (std::string failure = RunGnuplot(gp.str(), image); !failure.empty()) return where + failure;
  return "";
}

}  // namespace uavsim::results
