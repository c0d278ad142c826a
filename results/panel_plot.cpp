// Small multiples with gnuplot's multiplot: every panel placed by screen
// margins (so all plot areas have the same size whatever their tic labels),
// the shared ranges worked out here from all the data, the legend drawn by
// one more "plot" of undefined curves into a strip below the panels.
#include "results/panel_plot.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

#include "results/csv.h"
#include "results/figure_style.h"
#include "results/gnuplot.h"
#include "results/gnuplot_figure.h"

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
constexpr int kCharPx = 8;        // a character of a panel title, roughly
constexpr int kTitleCharPx = 9;   // a character of the figure title, roughly

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

// The curves as read: per panel (in first-seen order) the points of each
// series (names in first-seen order).
struct Panels {
  std::vector<std::string> series_names;
  std::vector<Panel> panels;
};

// The x, y and ci95 cells of a row into `p`: "" or why not (after `at`).
std::string ParsePoint(const std::string& x_cell, const std::string& y_cell,
                       const std::string& ci_cell, const PanelPlotSpec& spec, const std::string& at,
                       Point* p) {
  if (!ParseFiniteNumber(x_cell, &p->x)) return at + "expected a finite number in \"x\"";
  if (!y_cell.empty() && !ParseFiniteNumber(y_cell, &p->y))
    return at + "expected an empty cell or a finite number in \"y\"";
  if (!ci_cell.empty() && (!ParseFiniteNumber(ci_cell, &p->ci) || p->ci < 0.0))
    return at + "expected an empty cell or a finite number >= 0 in \"ci95\"";
  if (spec.log_x && p->x <= 0.0) return at + "x must be > 0 on a logarithmic axis";
  if (spec.log_y && !y_cell.empty() && p->y <= 0.0)
    return at + "y must be > 0 on a logarithmic axis";
  return "";
}

// The curves of `csv` into `out`: "" or why not (after `where`).
std::string ReadPanels(const CsvFile& csv, const PanelPlotSpec& spec, const std::string& where,
                       Panels* out) {
  long col[5];
  const char* names[5] = {"x", "y", "ci95", "series", "panel"};
  for (int k = 0; k < 5; ++k) {
    col[k] = csv.Column(names[k]);
    if (col[k] < 0) return where + "no column \"" + names[k] + "\"";
  }
  auto& series_names = out->series_names;
  auto& panels = out->panels;
  std::size_t drawn = 0;
  for (std::size_t r = 0; r < csv.rows.size(); ++r) {
    const std::vector<std::string>& cells = csv.rows[r];
    const std::string at = where + "line " + std::to_string(csv.line[r]) + ": ";
    Point p;
    const std::string& y_cell = cells[col[1]];
    if (std::string err = ParsePoint(cells[col[0]], y_cell, cells[col[2]], spec, at, &p);
        !err.empty())
      return err;

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
  return "";
}

struct SharedRanges {
  Range x, y;
  bool any_band = false;  // some point has a band
};

// Sorts every curve by x and works out the ranges all panels share.
SharedRanges SortAndRange(Panels& curves, const PanelPlotSpec& spec) {
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo;
  double y_lo = x_lo, y_hi = -x_lo;        // the points
  double band_lo = x_lo, band_hi = -x_lo;  // the points and their bands
  bool any_band = false;
  for (auto& panel : curves.panels)
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
  return {xr, yr, any_band};
}

// The layout in pixels: the figure's title, the grid of panels, the legend.
struct PanelLayout {
  PanelGrid grid;
  ScreenCoordinates screen;
  LegendStrip legend;
  std::vector<std::string> title_lines;
  int title_px = 0;                                   // the figure's title, above the panels
  std::vector<std::vector<std::string>> panel_lines;  // each panel's title
  int top_px = 0;                                     // a panel's top margin (its title)
};

// The layout of `curves` as `spec` says into `l`: "" or why it does not fit.
std::string LayOutPanels(const Panels& curves, const PanelPlotSpec& spec, bool any_band,
                         PanelLayout* l) {
  const int n = static_cast<int>(curves.panels.size());
  l->grid = ChoosePanelGrid(n, spec.max_columns);
  ScreenCoordinates& screen = l->screen;
  screen.width_px = kGutterPx + l->grid.columns * spec.panel_width_px + kEdgePx;
  std::vector<std::string> entries = curves.series_names;
  if (any_band) entries.push_back(spec.band_label);
  l->legend = SizeLegendStrip(screen.width_px, entries, 70, 18, !spec.legend_title.empty());
  // Titles wrapped to their width: the figure's above the panels, each
  // panel's above its plot area (all panels as tall as the tallest needs).
  l->title_lines = WrapWords(spec.title, (screen.width_px - 24) / kTitleCharPx);
  l->title_px = 12 + static_cast<int>(l->title_lines.size()) * kTitleLinePx +
                (l->title_lines.empty() ? 0 : 10);
  std::size_t most_panel_lines = 1;
  for (const auto& panel : curves.panels) {
    l->panel_lines.push_back(WrapWords(panel.name, (spec.panel_width_px - 16) / kCharPx));
    most_panel_lines = std::max(most_panel_lines, l->panel_lines.back().size());
  }
  l->top_px = kTopPx + kPanelLinePx * static_cast<int>(most_panel_lines - 1);
  screen.height_px = l->title_px + l->grid.rows * spec.panel_height_px + l->legend.height_px;
  if (screen.width_px > kMaxImagePx || screen.height_px > kMaxImagePx)
    return std::to_string(n) + " panels need a " + std::to_string(screen.width_px) + " x " +
           std::to_string(screen.height_px) + " image; the limit is " +
           std::to_string(kMaxImagePx) + " pixels";
  return "";
}

// Texts through variables: `title` and `set title` take string expressions
// there.
void WritePanelTexts(GnuplotFigure& figure, const Panels& curves, const PanelPlotSpec& spec,
                     const PanelLayout& l) {
  figure.TextLines("uavsim_title", l.title_lines);
  figure.Text("uavsim_xlabel", spec.x_label);
  figure.Text("uavsim_ylabel", spec.y_label);
  figure.Text("uavsim_key", spec.legend_title);
  figure.Text("uavsim_band", spec.band_label);
  for (std::size_t s = 0; s < curves.series_names.size(); ++s)
    figure.Text("uavsim_series" + std::to_string(s), curves.series_names[s]);
  for (std::size_t k = 0; k < l.panel_lines.size(); ++k)
    figure.TextLines("uavsim_panel" + std::to_string(k), l.panel_lines[k]);
}

// The data block of panel k's series s.
std::string PanelData(std::size_t k, std::size_t s) {
  return "p" + std::to_string(k) + "s" + std::to_string(s);
}

// Per panel and series: x, y, band bottom, band top (the bottom raised to the
// axis on a logarithmic axis, where y - ci95 may be <= 0).
void WritePanelData(GnuplotFigure& figure, const Panels& curves, const PanelPlotSpec& spec,
                    double y_lo) {
  figure.Commands() << "set datafile separator whitespace\n";
  for (std::size_t k = 0; k < curves.panels.size(); ++k)
    for (std::size_t s = 0; s < curves.panels[k].series.size(); ++s) {
      if (curves.panels[k].series[s].empty()) continue;
      std::string rows;
      for (const Point& p : curves.panels[k].series[s]) {
        const double ci = std::max(p.ci, 0.0);
        const double low = spec.log_y && p.y - ci <= y_lo ? y_lo : p.y - ci;
        rows += ShortestNumber(p.x) + " " + ShortestNumber(p.y) + " " + ShortestNumber(low) + " " +
                ShortestNumber(p.y + ci) + "\n";
      }
      figure.Data(PanelData(k, s), rows);
    }
}

// What every panel shares: the grid, tics, border, bands' fill and ranges.
void SetSharedAxes(GnuplotFigure& figure, const PanelPlotSpec& spec, const SharedRanges& ranges) {
  BeginMultiplot(figure, !spec.title.empty());
  std::ostream& gp = figure.Commands();
  gp << "set grid lt 1 lc rgb '#e3e3e3' lw 1\n"
     << "set tics out nomirror\n"
     << "set border 3 lc rgb '#444444'\n"
     << "set style fill transparent solid 0.2 noborder\n";
  if (spec.log_x) gp << "set logscale x\n";
  if (spec.log_y) gp << "set logscale y\n";
  gp << "set xrange [" << ShortestNumber(ranges.x.lo) << ":" << ShortestNumber(ranges.x.hi) << "]\n"
     << "set yrange [" << ShortestNumber(ranges.y.lo) << ":" << ShortestNumber(ranges.y.hi)
     << "]\n";
}

// Panel k in its cell: its title, the axis labels of the grid's edges, its
// bands and lines.
void PlotPanel(GnuplotFigure& figure, const Panels& curves, const PanelPlotSpec& spec,
               const PanelLayout& l, int k) {
  const int n = static_cast<int>(curves.panels.size());
  const int r = k / l.grid.columns, c = k % l.grid.columns;
  const int x0 = kGutterPx + c * spec.panel_width_px, y0 = l.title_px + r * spec.panel_height_px;
  figure.PlotArea(l.screen, x0 + kLeftPx, x0 + spec.panel_width_px - kRightPx, y0 + l.top_px,
                  y0 + spec.panel_height_px - kBottomPx);
  figure.Commands() << "set title uavsim_panel" << k
                    << " font ',12'\n"
                    // The x label under each column's lowest panel, the y label
                    // left of each row.
                    << (k + l.grid.columns >= n ? "set xlabel uavsim_xlabel\n" : "unset xlabel\n")
                    << (c == 0 ? "set ylabel uavsim_ylabel\n" : "unset ylabel\n");
  // Bands first, so that no band veils another series' line.
  std::vector<std::string> lines;
  const auto& series = curves.panels[k].series;
  for (std::size_t s = 0; s < series.size(); ++s) {
    if (series[s].empty()) continue;
    const std::string data = "$" + PanelData(k, s);
    const bool band =
        std::any_of(series[s].begin(), series[s].end(), [](const Point& p) { return p.ci > 0; });
    if (band)
      figure.Curve(data + " using 1:3:4 with filledcurves fc rgb '" +
                   kSeriesColours[s % kSeriesColourCount] + "' notitle");
    // Markers name the series; beyond 8 a line, every few suffice.
    const std::size_t interval = (series[s].size() + 7) / 8;
    lines.push_back(data + " using 1:2 with linespoints " + Style(s, interval) + " notitle");
  }
  if (lines.empty()) {
    figure.Commands() << "set label 1 'no values' at graph 0.5, 0.5 center tc rgb '#888888'\n"
                      << "plot NaN notitle\nunset label 1\n";
    return;
  }
  for (const std::string& line : lines) figure.Curve(line);
  figure.Plot();
}

// The legend: undefined curves in the strip below the panels.
void PlotPanelLegend(GnuplotFigure& figure, const Panels& curves, const PanelPlotSpec& spec,
                     const PanelLayout& l, bool any_band) {
  for (std::size_t s = 0; s < curves.series_names.size(); ++s)
    figure.Curve("NaN with linespoints " + Style(s) + " title uavsim_series" + std::to_string(s));
  if (any_band)
    figure.Curve(
        "NaN with filledcurves fc rgb '#555555' fs transparent solid 0.25 "
        "title uavsim_band");
  PlotLegendStrip(figure, l.screen, l.title_px + l.grid.rows * spec.panel_height_px + 4,
                  "unset title\n", 3, l.legend, !spec.legend_title.empty());
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

  CsvFile csv;
  if (std::string err = ReadCsvFile(csv_path, &csv); !err.empty()) return where + err;
  Panels curves;
  if (std::string err = ReadPanels(csv, spec, where, &curves); !err.empty()) return err;
  const SharedRanges ranges = SortAndRange(curves, spec);
  PanelLayout layout;
  if (std::string err = LayOutPanels(curves, spec, ranges.any_band, &layout); !err.empty())
    return where + err;

  GnuplotFigure figure;
  WritePanelTexts(figure, curves, spec, layout);
  WritePanelData(figure, curves, spec, ranges.y.lo);
  SetSharedAxes(figure, spec, ranges);
  for (int k = 0; k < static_cast<int>(curves.panels.size()); ++k)
    PlotPanel(figure, curves, spec, layout, k);
  PlotPanelLegend(figure, curves, spec, layout, ranges.any_band);
  const GnuplotImage image{png, layout.screen.width_px, layout.screen.height_px, "sans,11",
                           spec.gnuplot};
  if (std::string failure = figure.Draw(image); !failure.empty()) return where + failure;
  return "";
}

}  // namespace uavsim::results
