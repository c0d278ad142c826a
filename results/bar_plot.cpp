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
#include <sstream>
#include <string>
#include <vector>

#include "results/csv.h"
#include "results/figure_style.h"
#include "results/gnuplot.h"

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
constexpr int kCharPx = 8;         // a character of a legend entry, roughly
constexpr int kTicCharPx = 9;      // a character of an x tic label, generously ('+' is wide)
constexpr int kLinePx = 18;        // a line of a tic label
constexpr int kTicGapPx = 10;      // between the axis and its tic labels
constexpr int kXLabelPx = 26;      // the x label's line
constexpr int kKeyRowPx = 22;      // a row of the legend
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

// The pixel offsets as a screen coordinate ("at screen f").
struct Canvas {
  int width = 0, height = 0;
  std::string X(double px) const { return ShortestNumber(px / width); }
  std::string Y(double px_from_top) const { return ShortestNumber(1.0 - px_from_top / height); }
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

  // ---- Read and check the CSV.
  CsvFile csv;
  if (std::string err = ReadCsvFile(csv_path, &csv); !err.empty()) return where + err;
  const std::string* names[4] = {&spec.category_column, &spec.series_column, &spec.y_column,
                                 &spec.ci95_column};
  long col[4];
  for (int k = 0; k < 4; ++k) {
    col[k] = csv.Column(*names[k]);
    if (col[k] < 0) return where + "no column \"" + *names[k] + "\"";
  }

  std::vector<std::string> categories, series_names;
  std::vector<std::vector<Bar>> bars;  // by series index
  // The line of each (category, series) row seen, to refuse a second one.
  std::vector<std::vector<std::size_t>> line_of;
  std::size_t drawn = 0;
  for (std::size_t r = 0; r < csv.rows.size(); ++r) {
    const std::vector<std::string>& cells = csv.rows[r];
    const std::string at = where + "line " + std::to_string(csv.line[r]) + ": ";
    Bar bar;
    const std::string &y_cell = cells[col[2]], &ci_cell = cells[col[3]];
    if (!y_cell.empty() && !ParseFiniteNumber(y_cell, &bar.y))
      return at + "expected an empty cell or a finite number in \"" + spec.y_column + "\"";
    if (!ci_cell.empty() && (!ParseFiniteNumber(ci_cell, &bar.ci) || bar.ci < 0.0))
      return at + "expected an empty cell or a finite number >= 0 in \"" + spec.ci95_column + "\"";
    if (spec.log_y && !y_cell.empty() && bar.y <= 0.0)
      return at + "y must be > 0 on a logarithmic axis";

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

  // Series with a bar somewhere, in first-seen order: the slots of a group.
  std::vector<std::size_t> shown;
  for (std::size_t s = 0; s < bars.size(); ++s)
    if (!bars[s].empty()) shown.push_back(s);
  const std::size_t n_series = shown.size();
  const int n_categories = static_cast<int>(categories.size());

  // ---- The y range: the bars, their whiskers and (on a linear axis from
  // zero) the bars' foot at 0.
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  bool any_whisker = false;
  for (const auto& series : bars)
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

  // ---- Layout, from the top: the title, the plot, the x tic labels, the x
  // label, the legend.
  Canvas canvas{spec.width_px, spec.height_px};
  const std::vector<std::string> title_lines =
      WrapWords(spec.title, (canvas.width - 24) / kTitleCharPx);
  const int top_px =
      title_lines.empty() ? kTopPx : 12 + static_cast<int>(title_lines.size()) * kTitleLinePx + 14;
  int longest_category = 0;
  for (const auto& c : categories) longest_category = std::max(longest_category, Utf8Chars(c));
  // Level tic labels while the longest fits its group, else turned; a
  // turned label hangs left of its tic, so the plot moves right until the
  // first ones stay in the image.
  int left_px = kLeftPx;
  double group_px = static_cast<double>(canvas.width - left_px - kRightPx) / n_categories;
  const bool turned = longest_category * kTicCharPx + 12 > group_px;
  const double cos_t = std::cos(kTurnDeg * kPi / 180.0), sin_t = std::sin(kTurnDeg * kPi / 180.0);
  if (turned)
    for (int pass = 0; pass < 2; ++pass) {
      double overhang = 0.0;
      for (int k = 0; k < n_categories; ++k)
        overhang = std::max(overhang, Utf8Chars(categories[k]) * kTicCharPx * cos_t +
                                          kLinePx * sin_t - (k + 0.5) * group_px + 4.0);
      left_px = std::max(kLeftPx, static_cast<int>(std::ceil(overhang)));
      group_px = static_cast<double>(canvas.width - left_px - kRightPx) / n_categories;
    }
  const int tics_px =
      turned
          ? static_cast<int>(std::ceil(longest_category * kTicCharPx * sin_t + kLinePx * cos_t)) +
                kTicGapPx
          : kLinePx + kTicGapPx;
  const int x_label_px = spec.x_label.empty() ? 0 : kXLabelPx;
  const std::size_t entries = n_series + (any_whisker ? 1 : 0);
  int longest_entry = any_whisker ? Utf8Chars(spec.error_bar_label) : 0;
  for (std::size_t s : shown) longest_entry = std::max(longest_entry, Utf8Chars(series_names[s]));
  const int entry_px = kCharPx * longest_entry + 60;
  const int per_row = std::clamp((canvas.width - 40) / entry_px, 1, static_cast<int>(entries));
  const int key_rows = (static_cast<int>(entries) + per_row - 1) / per_row;
  const int key_px = 14 + (spec.legend_title.empty() ? 0 : kKeyRowPx) + key_rows * kKeyRowPx;
  const int plot_bottom_px = canvas.height - key_px - x_label_px - tics_px - 8;
  const int plot_width_px = canvas.width - left_px - kRightPx;
  if (plot_bottom_px - top_px < kMinPlotPx || plot_width_px < kMinPlotPx)
    return where + "a " + std::to_string(canvas.width) + " x " + std::to_string(canvas.height) +
           " image leaves no room for the bars beside their labels and legend (" +
           std::to_string(n_categories) + " categories, the longest of " +
           std::to_string(longest_category) + " characters, " + std::to_string(n_series) +
           " series): make it larger";

  // ---- The script. Texts through variables: `title`, `set label` and the
  // tic list take string expressions there.
  std::ostringstream gp;
  gp << "uavsim_title = " << GnuplotLines(title_lines) << "\n"
     << "uavsim_xlabel = " << GnuplotString(spec.x_label) << "\n"
     << "uavsim_ylabel = " << GnuplotString(spec.y_label) << "\n"
     << "uavsim_key = " << GnuplotString(spec.legend_title) << "\n"
     << "uavsim_ci = " << GnuplotString(spec.error_bar_label) << "\n";
  for (int k = 0; k < n_categories; ++k)
    gp << "uavsim_category" << k << " = " << GnuplotString(categories[k]) << "\n";
  for (std::size_t s : shown)
    gp << "uavsim_series" << s << " = " << GnuplotString(series_names[s]) << "\n";
  gp << "set datafile separator whitespace\n";
  // Per series: its bars (category index, y) and its whiskers (category
  // index, y, bottom, top; the bottom raised to the axis on a logarithmic
  // axis, where y - ci95 may be <= 0).
  for (std::size_t s : shown) {
    gp << "$bars" << s << " << EOD\n";
    for (const Bar& b : bars[s]) gp << b.category << " " << ShortestNumber(b.y) << "\n";
    gp << "EOD\n";
    if (std::none_of(bars[s].begin(), bars[s].end(), [](const Bar& b) { return b.ci > 0.0; }))
      continue;
    gp << "$whiskers" << s << " << EOD\n";
    for (const Bar& b : bars[s]) {
      if (b.ci <= 0.0) continue;
      const double low = spec.log_y && b.y - b.ci <= y_lo ? y_lo : b.y - b.ci;
      gp << b.category << " " << ShortestNumber(b.y) << " " << ShortestNumber(low) << " "
         << ShortestNumber(b.y + b.ci) << "\n";
    }
    gp << "EOD\n";
  }

  gp << "set multiplot" << (title_lines.empty() ? "" : " title uavsim_title font ',14'") << "\n"
     << "unset key\n"
     << "set lmargin at screen " << canvas.X(left_px) << "\n"
     << "set rmargin at screen " << canvas.X(canvas.width - kRightPx) << "\n"
     << "set tmargin at screen " << canvas.Y(top_px) << "\n"
     << "set bmargin at screen " << canvas.Y(plot_bottom_px) << "\n"
     << "set ylabel uavsim_ylabel\n"
     << "set grid ytics back lt 1 lc rgb '#e3e3e3' lw 1\n"
     << "set border 3 lc rgb '#444444'\n"
     << "set ytics out nomirror\n"
     << "set xtics scale 0 nomirror"
     << (turned ? " rotate by " + ShortestNumber(kTurnDeg) + " right" : std::string(" norotate"))
     << " (";
  for (int k = 0; k < n_categories; ++k)
    gp << (k ? ", " : "") << "uavsim_category" << k << " " << k;
  gp << ")\n";
  if (!spec.x_label.empty())
    gp << "set label 1 uavsim_xlabel at screen " << canvas.X(left_px + plot_width_px / 2.0)
       << ", screen " << canvas.Y(plot_bottom_px + tics_px + x_label_px / 2.0) << " center\n";
  if (spec.log_y) gp << "set logscale y\n";
  // Groups one unit apart, the slots of a group side by side about its
  // centre.
  const double group = n_series == 1 ? kLoneBarFill : kGroupFill;
  const double slot = group / static_cast<double>(n_series);
  gp << "set xrange [-0.5:" << ShortestNumber(n_categories - 0.5) << "]\n"
     << "set yrange [" << ShortestNumber(y_lo) << ":" << ShortestNumber(y_hi) << "]\n"
     << "set boxwidth " << ShortestNumber(slot * kBoxFill) << " absolute\n";
  // Whiskers as two-headed arrows with flat heads: "with yerrorbars" would
  // leave a gap around the bar's top (gnuplot's point clearance).
  const double cap_px = std::clamp(0.25 * slot * kBoxFill * group_px, 2.0, 6.0);
  const std::string whisker = "with vectors heads size screen " + canvas.X(cap_px) +
                              ",90 lc rgb '" + kEdgeColour + "' lw 1.5";
  std::vector<std::string> boxes, whiskers;
  for (std::size_t i = 0; i < n_series; ++i) {
    const std::size_t s = shown[i];
    const double offset = (static_cast<double>(i) - (n_series - 1) / 2.0) * slot;
    const std::string x = "($1+(" + ShortestNumber(offset) + "))";
    boxes.push_back("$bars" + std::to_string(s) + " using " + x + ":2 with boxes " + BoxStyle(s) +
                    " notitle");
    if (std::any_of(bars[s].begin(), bars[s].end(), [](const Bar& b) { return b.ci > 0.0; }))
      whiskers.push_back("$whiskers" + std::to_string(s) + " using " + x + ":3:(0):($4-$3) " +
                         whisker + " notitle");
  }
  // Whiskers last, so that no neighbouring box covers one.
  boxes.insert(boxes.end(), whiskers.begin(), whiskers.end());
  gp << "plot ";
  for (std::size_t i = 0; i < boxes.size(); ++i) gp << (i ? ", \\\n     " : "") << boxes[i];
  gp << "\n";

  // The legend: undefined curves in the strip below the x label.
  gp << "set lmargin at screen 0\nset rmargin at screen 1\n"
     << "set tmargin at screen " << canvas.Y(canvas.height - key_px)
     << "\nset bmargin at screen 0\n"
     << "unset label 1\nunset xlabel\nunset ylabel\nunset logscale\nunset grid\nunset border\n"
     << "unset tics\nset xrange [0:1]\nset yrange [0:1]\n"
     << "set key center center horizontal Left reverse samplen 2 spacing 1.1 width 1 maxcols "
     << per_row << (spec.legend_title.empty() ? "" : " title uavsim_key") << "\n"
     << "plot ";
  for (std::size_t i = 0; i < n_series; ++i)
    gp << (i ? ", \\\n     " : "") << "NaN with boxes " << BoxStyle(shown[i])
       << " title uavsim_series" << shown[i];
  if (any_whisker) gp << ", \\\n     NaN " << whisker << " title uavsim_ci";
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
