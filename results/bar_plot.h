// A grouped bar chart: one group of bars per category along x, one bar per
// series in each group, with whiskers for the 95 % confidence interval of
// each bar (e.g. the RMSE of several methods for each modality combination).
//
// The CSV is the plain kind results/ writes (a header row, comma-separated,
// no quoting) with at least the columns (names as in the spec)
//
//   category  the group's name, its label under the x axis
//   series    the bar's name within the group, its legend entry
//   y         a finite number (> 0 on a logarithmic y axis); empty = a
//             missing bar, left out (its slot in the group stays empty)
//   ci95      the half-width of the bar's 95 % confidence interval: a finite
//             number >= 0, drawn as a whisker from y - ci95 to y + ci95; empty
//             or 0 = no whisker
//
// in any order (other columns are ignored), at most one row per category and
// series. Categories appear in first-seen order along x, every one with a
// slot (even one without any bar); series in first-seen order within each
// group, every group with a slot for every series that has a bar somewhere
// (a series with no bar anywhere is left out, of the legend too). A series
// keeps one colour (Tableau 10, as in results/panel_plot.h; after ten the
// bars are hatched), and one legend sits in a strip below the plot. The x tic
// labels are turned by 45 degrees when a level one would be wider than its
// group. Texts go into the script as gnuplot string literals
// (results/gnuplot.h), the data as inline data blocks.
#pragma once

#include <string>

namespace uavsim::results {

struct BarPlotSpec {
  std::string title;         // above the plot ("" = none)
  std::string x_label;       // e.g. "Modalities" ("" = none)
  std::string y_label;       // with its unit, e.g. "RMSE (m)"
  std::string legend_title;  // e.g. "method" ("" = none)
  // The legend entry of the whiskers (shown when some whisker is drawn).
  std::string error_bar_label = "95 % CI of the mean";
  std::string png_path;             // "" = the CSV path with its extension replaced by ".png"
  int width_px = 900;               // the image: 320 .. 8192
  int height_px = 560;              // 240 .. 8192
  std::string gnuplot = "gnuplot";  // the program; searched on PATH unless it contains '/'
  bool log_y = false;               // logarithmic y axis (bars rise from its bottom)
  bool y_min_zero = true;           // the y axis includes 0 (not with log_y)
  // The CSV's column names.
  std::string category_column = "category";
  std::string series_column = "series";
  std::string y_column = "y";
  std::string ci95_column = "ci95";
};

// Draws `csv_path` as `spec` says into a PNG (written under a temporary name
// and renamed: a failed plot leaves no PNG behind, an older one untouched).
// Returns "" on success, else one line starting "bar plot <csv>: ": the CSV
// unreadable or empty, a column missing, a row of the wrong width, a cell
// that is not a number as above, a second row for a category and series, no
// bar to draw, a bad image size or one too small for its labels and legend,
// gnuplot missing or failing (with the first line it printed). Never throws
// for these; blocks until gnuplot exits.
std::string PlotBars(const std::string& csv_path, const BarPlotSpec& spec);

}  // namespace uavsim::results
