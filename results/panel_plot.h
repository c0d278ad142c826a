// Small multiples: a long CSV drawn as a grid of panels that share their
// axes, one panel per value of its `panel` column, the same curves in each.
//
// The CSV is the plain kind results/ writes (a header row, comma-separated,
// no quoting) with at least the columns
//
//   x       a finite number (> 0 on a logarithmic x axis)
//   y       a finite number (> 0 on a logarithmic y axis); empty = a missing
//           point, left out (the line joins its neighbours)
//   ci95    the half-width of the point's 95 % confidence interval: a finite
//           number >= 0, or empty = no band at that point
//   series  the curve's name
//   panel   the panel's name (also its title)
//
// in any order (other columns are ignored). Panels appear in first-seen
// order, left to right, top to bottom; each draws every series it has
// values of as a line with points over a translucent band from y - ci95 to
// y + ci95. A series keeps one colour and point shape in every panel, and
// one legend for the whole figure sits in a strip below the panels. The
// panels share their x and y ranges, so they compare at a glance. Texts go
// into the script as gnuplot string literals (results/gnuplot.h), the data
// as inline data blocks.
#pragma once

#include <limits>
#include <string>

namespace uavsim::results {

struct PanelPlotSpec {
  std::string title;         // the figure's, above the panels ("" = none)
  std::string x_label;       // with its unit, e.g. "Uplink packet loss probability"
  std::string y_label;       // e.g. "RMSE (m)"
  std::string legend_title;  // e.g. "method" ("" = none)
  // The legend entry of the shaded bands (shown when some band is drawn).
  std::string band_label = "95 % CI of the mean";
  std::string png_path;      // "" = the CSV path with its extension replaced by ".png"
  int panel_width_px = 420;  // each panel's cell; the image grows with the panel count
  int panel_height_px = 320;
  int max_columns = 3;              // panels per row at most (>= 1)
  std::string gnuplot = "gnuplot";  // the program; searched on PATH unless it contains '/'
  bool log_x = false;               // logarithmic x axis
  bool log_y = false;               // logarithmic y axis
  bool y_min_zero = false;          // the y axis starts at 0 (not with log_y)
  // The top of the y axis at most (bands beyond it are cut, points never):
  // e.g. 1 for shares. NaN = from the data alone.
  double y_max = std::numeric_limits<double>::quiet_NaN();
};

// Rows and columns of the panel grid: as few rows as `max_columns` allows,
// then the columns balanced over them (4 panels: 2 x 2; 5: 3 + 2; 15 with
// max_columns 3: 5 rows of 3). 0 panels: 0 x 0.
struct PanelGrid {
  int columns = 0;
  int rows = 0;
};
PanelGrid ChoosePanelGrid(int panels, int max_columns);

// Draws `csv_path` as `spec` says into a PNG (written under a temporary name
// and renamed: a failed plot leaves no PNG behind, an older one untouched).
// Returns "" on success, else one line starting "panel plot <csv>: ": the
// CSV unreadable or empty, a column missing, a row of the wrong width, a
// cell that is not a number as above, no row with a y value, a bad spec or
// an image beyond 8192 pixels, gnuplot missing or failing (with the first
// line it printed). Never throws for these; blocks until gnuplot exits.
std::string PlotPanels(const std::string& csv_path, const PanelPlotSpec& spec);

}  // namespace uavsim::results
