// Bars drawn "with boxes" at positions worked out here (category index plus
// the series' offset in its group) rather than as a gnuplot histogram: a
// missing bar is then a row left out, its slot kept by the others' fixed
// offsets, and the whiskers (at the same offsets) sit on their bars'
// centres. The layout is fixed in pixels from the image size as
// in panel_plot.cpp: the plot by screen margins, the x label as a label
// below the (perhaps turned) tic labels, the legend by one more "plot" of
// undefined curves into a strip below.
#include "results/bar_plot.h"

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

constexpr int kMinWidthPx = 320, kMinHeightPx = 240, kMaxImagePx = 8192;

// Pixels of the layout (the font is sans 11).
constexpr int kLeftPx = 84;        // the y label and the y tic labels
constexpr int kRightPx = 20;       // right of the plot
constexpr int kTopPx = 16;         // above the plot without a title
constexpr int kTitleLinePx = 22;   // a line of the title (sans 14)
constexpr int kTitleCharPx = 9;    // a character of the title, roughly
constexpr int kTicCharPx = 9;      // a character of an x tic label, generously ('+' is wide)
constexpr int kLinePx = 18;        // a line of a tic label
constexpr int kTicGapPx = 10;      // between the axis and its tic labels
constexpr int kXLabelPx = 26;      // the x label's line
constexpr int kMinPlotPx = 100;    // the plot area at least, either way
constexpr double kTurnDeg = 45.0;  // turned x tic labels
constexpr double kPi = 3.14159265358979323846;

// The share of a category's width its group of bars fills.
constexpr double kGroupFill = 0.8, kLoneBarFill = 0.6;
// The share of a bar's slot its box fills (a gap between neighbours).
constexpr double kBoxFill = 0.88;

constexpr const char* kEdgeColour = "#333333";  // box borders and whiskers

struct Bar {
  std::size_t category = 0;
  double y = 0.0;
  double ci = 0.0;  // 0: no whisker
};

// The colour and fill of series number `series`: hatched after ten.
std::string BoxStyle(std::size_t series) {
  std::string s = "lc rgb '" + std::string(kSeriesColours[series % kSeriesColourCount]) + "' fs ";
  if (series < static_cast<std::size_t>(kSeriesColourCount))
    s += "solid 0.85";
  else
    s += "pattern " + std::to_string(1 + (series / kSeriesColourCount - 1) % 7);
  return s + " border lc rgb '" + kEdgeColour + "'";
}

// Bars as read: one list per series, with the categories and series names
// in first-seen order.
struct Bars {
  std::vector<std::string> categories, series_names;
  std::vector<std::vector<Bar>> by_series;  // by series index
  // Series with a bar somewhere, in first-seen order: the slots of a group.
  std::vector<std::size_t> shown;
};

bool HasWhisker(const std::vector<Bar>& bars) {
  return std::any_of(bars.begin(), bars.end(), [](const Bar& b) { return b.ci > 0.0; });
}

// The y and ci95 cells of a row into `bar`: "" or why not (after `at`).
std::string ParseBarValues(const std::string& y_cell, const std::string& ci_cell,
                           const BarPlotSpec& spec, const std::string& at, Bar* bar) {
  if (!y_cell.empty() && !ParseFiniteNumber(y_cell, &bar->y))
    return at + "expected an empty cell or a finite number in \"" + spec.y_column + "\"";
  if (!ci_cell.empty() && (!ParseFiniteNumber(ci_cell, &bar->ci) || bar->ci < 0.0))
    return at + "expected an empty cell or a finite number >= 0 in \"" + spec.ci95_column + "\"";
  if (spec.log_y && !y_cell.empty() && bar->y <= 0.0)
    return at + "y must be > 0 on a logarithmic axis";
  return "";
}

// The bars of `csv` into `out`: "" or why not (after `where`).
std::string ReadBars(const CsvFile& csv, const BarPlotSpec& spec, const std::string& where,
                     Bars* out) {
  const std::string* names[4] = {&spec.category_column, &spec.series_column, &spec.y_column,
                                 &spec.ci95_column};
  long col[4];
  for (int k = 0; k < 4; ++k) {
    col[k] = csv.Column(*names[k]);
    if (col[k] < 0) return where + "no column \"" + *names[k] + "\"";
  }
  auto& categories = out->categories;
  auto& series_names = out->series_names;
  auto& bars = out->by_series;
  // The line of each (category, series) row seen, to refuse a second one.
  std::vector<std::vector<std::size_t>> line_of;
  std::size_t drawn = 0;
  for (std::size_t r = 0; r < csv.rows.size(); ++r) {
    const std::vector<std::string>& cells = csv.rows[r];
    const std::string at = where + "line " + std::to_string(csv.line[r]) + ": ";
    Bar bar;
    const std::string &y_cell = cells[col[2]], &ci_cell = cells[col[3]];
    if (std::string err = ParseBarValues(y_cell, ci_cell, spec, at, &bar); !err.empty()) return err;

    const std::string &category = cells[col[0]], &series = cells[col[1]];
    bar.category = static_cast<std::size_t>(
        std::find(categories.begin(), categories.end(), category) - categories.begin());
    if (bar.category == categories.size()) categories.push_back(category);
    const auto s = static_cast<std::size_t>(
        std::find(series_names.begin(), series_names.end(), series) - series_names.begin());
    if (s == series_names.size()) {
      series_names.push_back(series);
      bars.emplace_back();
      line_of.emplace_back();
    }
    if (line_of[s].size() <= bar.category) line_of[s].resize(bar.category + 1, 0);
    if (const std::size_t first = line_of[s][bar.category]; first != 0)
      return at + "a second row for category \"" + category + "\" and series \"" + series +
             "\" (the first on line " + std::to_string(first) + ")";
    line_of[s][bar.category] = csv.line[r];
    if (y_cell.empty()) continue;  // a missing bar
    bars[s].push_back(bar);
    ++drawn;
  }
  if (drawn == 0) return where + "no bar to draw (every \"" + spec.y_column + "\" cell is empty)";
  for (std::size_t s = 0; s < bars.size(); ++s)
    if (!bars[s].empty()) out->shown.push_back(s);
  return "";
}

struct YRange {
  double lo = 0.0, hi = 0.0;
  bool any_whisker = false;  // some bar has a whisker
};

// The y range: the bars, their whiskers and (on a linear axis from zero) the
// bars' foot at 0.
YRange BarYRange(const Bars& bars, const BarPlotSpec& spec) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  bool any_whisker = false;
  for (const auto& series : bars.by_series)
    for (const Bar& b : series) {
      any_whisker = any_whisker || b.ci > 0.0;
      hi = std::max(hi, b.y + b.ci);
      lo = std::min(lo, spec.log_y && b.y - b.ci <= 0.0 ? b.y : b.y - b.ci);
    }
  double y_lo = 0.0, y_hi = 0.0;
  if (spec.log_y) {
    const double f = hi > lo ? std::pow(hi / lo, 0.05) : 1.5;
    y_lo = lo / f, y_hi = hi * f;
  } else {
    const bool from_zero = spec.y_min_zero;
    if (from_zero) lo = std::min(lo, 0.0), hi = std::max(hi, 0.0);
    const double pad = hi > lo ? 0.05 * (hi - lo) : (lo != 0.0 ? 0.1 * std::abs(lo) : 1.0);
    y_lo = from_zero && lo == 0.0 ? 0.0 : lo - pad;
    y_hi = from_zero && hi == 0.0 ? 0.0 : hi + pad;
  }
  return {y_lo, y_hi, any_whisker};
}

// The layout in pixels, from the top: the title, the plot, the x tic labels,
// the x label, the legend.
struct BarLayout {
  ScreenCoordinates screen;
  std::vector<std::string> title_lines;
  int top_px = 0;            // the plot's top
  int longest_category = 0;  // characters
  int left_px = kLeftPx;     // the plot's left
  double group_px = 0.0;     // a category's width
  bool turned = false;       // the x tic labels turned by kTurnDeg
  int tics_px = 0;           // the x tic labels' height
  int x_label_px = 0;
  LegendStrip legend;
  int plot_bottom_px = 0, plot_width_px = 0;
};

// Level tic labels while the longest fits its group, else turned; a turned
// label hangs left of its tic, so the plot moves right until the first ones
// stay in the image.
void LayOutTicLabels(const std::vector<std::string>& categories, BarLayout* l) {
  const int n_categories = static_cast<int>(categories.size());
  const int width = l->screen.width_px;
  int longest_category = 0;
  for (const auto& c : categories) longest_category = std::max(longest_category, Utf8Chars(c));
  int left_px = kLeftPx;
  double group_px = static_cast<double>(width - left_px - kRightPx) / n_categories;
  const bool turned = longest_category * kTicCharPx + 12 > group_px;
  const double cos_t = std::cos(kTurnDeg * kPi / 180.0), sin_t = std::sin(kTurnDeg * kPi / 180.0);
  if (turned)
    for (int pass = 0; pass < 2; ++pass) {
      double overhang = 0.0;
      for (int k = 0; k < n_categories; ++k)
        overhang = std::max(overhang, Utf8Chars(categories[k]) * kTicCharPx * cos_t +
                                          kLinePx * sin_t - (k + 0.5) * group_px + 4.0);
      left_px = std::max(kLeftPx, static_cast<int>(std::ceil(overhang)));
      group_px = static_cast<double>(width - left_px - kRightPx) / n_categories;
    }
  l->longest_category = longest_category;
  l->left_px = left_px;
  l->group_px = group_px;
  l->turned = turned;
  l->tics_px =
      turned
          ? static_cast<int>(std::ceil(longest_category * kTicCharPx * sin_t + kLinePx * cos_t)) +
                kTicGapPx
          : kLinePx + kTicGapPx;
}

// The layout of `bars` as `spec` says into `l`: "" or why it does not fit.
std::string LayOutBars(const Bars& bars, const BarPlotSpec& spec, bool any_whisker, BarLayout* l) {
  l->screen = {spec.width_px, spec.height_px};
  const ScreenCoordinates& screen = l->screen;
  l->title_lines = WrapWords(spec.title, (screen.width_px - 24) / kTitleCharPx);
  l->top_px = l->title_lines.empty()
                  ? kTopPx
                  : 12 + static_cast<int>(l->title_lines.size()) * kTitleLinePx + 14;
  LayOutTicLabels(bars.categories, l);
  l->x_label_px = spec.x_label.empty() ? 0 : kXLabelPx;
  std::vector<std::string> entries;
  for (std::size_t s : bars.shown) entries.push_back(bars.series_names[s]);
  if (any_whisker) entries.push_back(spec.error_bar_label);
  l->legend = SizeLegendStrip(screen.width_px, entries, 60, 14, !spec.legend_title.empty());
  l->plot_bottom_px = screen.height_px - l->legend.height_px - l->x_label_px - l->tics_px - 8;
  l->plot_width_px = screen.width_px - l->left_px - kRightPx;
  if (l->plot_bottom_px - l->top_px < kMinPlotPx || l->plot_width_px < kMinPlotPx)
    return "a " + std::to_string(screen.width_px) + " x " + std::to_string(screen.height_px) +
           " image leaves no room for the bars beside their labels and legend (" +
           std::to_string(bars.categories.size()) + " categories, the longest of " +
           std::to_string(l->longest_category) + " characters, " +
           std::to_string(bars.shown.size()) + " series): make it larger";
  return "";
}

// Texts through variables: `title`, `set label` and the tic list take string
// expressions there.
void WriteBarTexts(GnuplotFigure& figure, const Bars& bars, const BarPlotSpec& spec,
                   const BarLayout& l) {
  figure.TextLines("uavsim_title", l.title_lines);
  figure.Text("uavsim_xlabel", spec.x_label);
  figure.Text("uavsim_ylabel", spec.y_label);
  figure.Text("uavsim_key", spec.legend_title);
  figure.Text("uavsim_ci", spec.error_bar_label);
  for (std::size_t k = 0; k < bars.categories.size(); ++k)
    figure.Text("uavsim_category" + std::to_string(k), bars.categories[k]);
  for (std::size_t s : bars.shown)
    figure.Text("uavsim_series" + std::to_string(s), bars.series_names[s]);
}

// Per series: its bars (category index, y) and its whiskers (category index,
// y, bottom, top; the bottom raised to the axis on a logarithmic axis, where
// y - ci95 may be <= 0).
void WriteBarData(GnuplotFigure& figure, const Bars& bars, const BarPlotSpec& spec, double y_lo) {
  figure.Commands() << "set datafile separator whitespace\n";
  for (std::size_t s : bars.shown) {
    std::string rows;
    for (const Bar& b : bars.by_series[s])
      rows += std::to_string(b.category) + " " + ShortestNumber(b.y) + "\n";
    figure.Data("bars" + std::to_string(s), rows);
    if (!HasWhisker(bars.by_series[s])) continue;
    std::string whiskers;
    for (const Bar& b : bars.by_series[s]) {
      if (b.ci <= 0.0) continue;
      const double low = spec.log_y && b.y - b.ci <= y_lo ? y_lo : b.y - b.ci;
      whiskers += std::to_string(b.category) + " " + ShortestNumber(b.y) + " " +
                  ShortestNumber(low) + " " + ShortestNumber(b.y + b.ci) + "\n";
    }
    figure.Data("whiskers" + std::to_string(s), whiskers);
  }
}

// The width of a bar's slot: groups one unit apart, the slots of a group side
// by side about its centre.
double SlotWidth(std::size_t n_series) {
  const double group = n_series == 1 ? kLoneBarFill : kGroupFill;
  return group / static_cast<double>(n_series);
}

// The plot area, the axes with their labels and ranges.
void SetBarAxes(GnuplotFigure& figure, const Bars& bars, const BarPlotSpec& spec,
                const BarLayout& l, const YRange& y) {
  const ScreenCoordinates& screen = l.screen;
  const int n_categories = static_cast<int>(bars.categories.size());
  BeginMultiplot(figure, !l.title_lines.empty());
  figure.PlotArea(screen, l.left_px, screen.width_px - kRightPx, l.top_px, l.plot_bottom_px);
  std::ostream& gp = figure.Commands();
  gp << "set ylabel uavsim_ylabel\n"
     << "set grid ytics back lt 1 lc rgb '#e3e3e3' lw 1\n"
     << "set border 3 lc rgb '#444444'\n"
     << "set ytics out nomirror\n"
     << "set xtics scale 0 nomirror"
     << (l.turned ? " rotate by " + ShortestNumber(kTurnDeg) + " right" : std::string(" norotate"))
     << " (";
  for (int k = 0; k < n_categories; ++k)
    gp << (k ? ", " : "") << "uavsim_category" << k << " " << k;
  gp << ")\n";
  if (!spec.x_label.empty())
    gp << "set label 1 uavsim_xlabel at screen " << screen.X(l.left_px + l.plot_width_px / 2.0)
       << ", screen " << screen.Y(l.plot_bottom_px + l.tics_px + l.x_label_px / 2.0) << " center\n";
  if (spec.log_y) gp << "set logscale y\n";
  gp << "set xrange [-0.5:" << ShortestNumber(n_categories - 0.5) << "]\n"
     << "set yrange [" << ShortestNumber(y.lo) << ":" << ShortestNumber(y.hi) << "]\n"
     << "set boxwidth " << ShortestNumber(SlotWidth(bars.shown.size()) * kBoxFill) << " absolute\n";
}

// Whiskers as two-headed arrows with flat heads: "with yerrorbars" would
// leave a gap around the bar's top (gnuplot's point clearance).
std::string WhiskerStyle(const Bars& bars, const BarLayout& l) {
  const double slot = SlotWidth(bars.shown.size());
  const double cap_px = std::clamp(0.25 * slot * kBoxFill * l.group_px, 2.0, 6.0);
  return "with vectors heads size screen " + l.screen.X(cap_px) + ",90 lc rgb '" + kEdgeColour +
         "' lw 1.5";
}

// The boxes at their slots' offsets, then the whiskers, so that no
// neighbouring box covers one.
void PlotBarsAndWhiskers(GnuplotFigure& figure, const Bars& bars, const BarLayout& l) {
  const std::size_t n_series = bars.shown.size();
  const double slot = SlotWidth(n_series);
  const std::string whisker = WhiskerStyle(bars, l);
  std::vector<std::string> whiskers;
  for (std::size_t i = 0; i < n_series; ++i) {
    const std::size_t s = bars.shown[i];
    const double offset = (static_cast<double>(i) - (n_series - 1) / 2.0) * slot;
    const std::string x = "($1+(" + ShortestNumber(offset) + "))";
    figure.Curve("$bars" + std::to_string(s) + " using " + x + ":2 with boxes " + BoxStyle(s) +
                 " notitle");
    if (HasWhisker(bars.by_series[s]))
      whiskers.push_back("$whiskers" + std::to_string(s) + " using " + x + ":3:(0):($4-$3) " +
                         whisker + " notitle");
  }
  for (const std::string& w : whiskers) figure.Curve(w);
  figure.Plot();
}

// The legend: undefined curves in the strip below the x label.
void PlotBarLegend(GnuplotFigure& figure, const Bars& bars, const BarPlotSpec& spec,
                   const BarLayout& l, bool any_whisker) {
  for (std::size_t s : bars.shown)
    figure.Curve("NaN with boxes " + BoxStyle(s) + " title uavsim_series" + std::to_string(s));
  if (any_whisker) figure.Curve("NaN " + WhiskerStyle(bars, l) + " title uavsim_ci");
  PlotLegendStrip(figure, l.screen, l.screen.height_px - l.legend.height_px, "unset label 1\n", 2,
                  l.legend, !spec.legend_title.empty());
}

}  // namespace

std::string PlotBars(const std::string& csv_path, const BarPlotSpec& spec) {
  const std::string where = "bar plot " + csv_path + ": ";
  if (spec.width_px < kMinWidthPx || spec.height_px < kMinHeightPx || spec.width_px > kMaxImagePx ||
      spec.height_px > kMaxImagePx)
    return where + "the image must be at least " + std::to_string(kMinWidthPx) + " x " +
           std::to_string(kMinHeightPx) + " and at most " + std::to_string(kMaxImagePx) + " x " +
           std::to_string(kMaxImagePx) + " pixels";
  const std::string png =
      spec.png_path.empty() ? fs::path(csv_path).replace_extension(".png").string() : spec.png_path;

  CsvFile csv;
  if (std::string err = ReadCsvFile(csv_path, &csv); !err.empty()) return where + err;
  Bars bars;
  if (std::string err = ReadBars(csv, spec, where, &bars); !err.empty()) return err;
  const YRange y = BarYRange(bars, spec);
  BarLayout layout;
  if (std::string err = LayOutBars(bars, spec, y.any_whisker, &layout); !err.empty())
    return where + err;

  GnuplotFigure figure;
  WriteBarTexts(figure, bars, spec, layout);
  WriteBarData(figure, bars, spec, y.lo);
  SetBarAxes(figure, bars, spec, layout, y);
  PlotBarsAndWhiskers(figure, bars, layout);
  PlotBarLegend(figure, bars, spec, layout, y.any_whisker);
  const GnuplotImage image{png, layout.screen.width_px, layout.screen.height_px, "sans,11",
                           spec.gnuplot};
  if (std::string failure = figure.Draw(image); !failure.empty()) return where + failure;
  return "";
}

}  // namespace uavsim::results
