// A small gnuplot driver: draws columns of a CSV file as lines, one line per
// value of a grouping column, into a PNG beside the CSV. Plotting only reads
// the CSV (as ns-3 keeps data writers and plot helpers apart).
//
// The CSV is the plain kind results/ and channel/ write: a header row of
// column names, comma-separated, no quoting. The data go into the gnuplot
// script as inline data blocks, and every text (title, labels, line names,
// the output path) as single-quoted gnuplot literals, in which gnuplot
// performs no substitution (no backquote commands, no macros, no escapes);
// control characters in texts are replaced by spaces. gnuplot runs without a
// shell, on a script in a temporary file.
//
// Optionally a column of error-bar half-widths (drawn "with yerrorlines"),
// missing y values (empty cells, left out), a logarithmic x axis, a y axis
// from 0 and the legend below the graph.
#pragma once

#include <string>

namespace uavsim::results {

struct PlotSpec {
  std::string title;
  std::string x_label;   // with its unit, e.g. "SNR (dB)"
  std::string y_label;   // e.g. "Rate (bit/s/Hz)"
  std::string x_column;  // header names of the CSV
  std::string y_column;
  std::string group_column;  // one line per distinct value, in first-seen order; "" = one line
  std::string png_path;      // "" = the CSV path with its extension replaced by ".png"
  int width_px = 800;        // 64 .. 8192
  int height_px = 560;       // 64 .. 8192
  std::string gnuplot = "gnuplot";  // the program; searched on PATH unless it contains '/'
  // "" = no error bars; else the column of each point's error-bar half-width
  // (a finite number >= 0; an empty cell = 0), drawn "with yerrorlines".
  // A small margin is added at both ends of the x range so that no bar sits
  // on the border.
  std::string y_error_column;
  // An empty y cell is a missing value: its row is left out (a line joins its
  // neighbours; a group with no value left draws no line). Off: an error, as
  // any cell that is not a finite number is either way.
  bool skip_empty_y = false;
  bool log_x = false;       // logarithmic x axis; every x must then be > 0
  bool log_y = false;       // logarithmic y axis; every y must then be > 0
  bool y_min_zero = false;  // the y axis starts at 0 (its top is automatic; not with log_y)
  bool key_below = false;   // the legend below the graph (else inside, top left)
};

// Draws `csv_path` as `spec` says. Uses gnuplot's pngcairo terminal when
// gnuplot has it, else png. The PNG is written under a temporary name beside
// its final one and renamed, so a failed plot leaves no PNG behind (and an
// older one untouched). Returns "" on success, else a one-line message:
// gnuplot missing, the CSV unreadable or empty, a column missing, a cell not
// a finite number (or a negative error bar, or x <= 0 on a logarithmic axis),
// no row left to draw, gnuplot failing (with the first line it printed). Never
// throws for these; blocks until gnuplot exits.
std::string PlotCsv(const std::string& csv_path, const PlotSpec& spec);

}  // namespace uavsim::results
