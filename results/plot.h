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
};

// Draws `csv_path` as `spec` says. Uses gnuplot's pngcairo terminal when
// gnuplot has it, else png. The PNG is written under a temporary name beside
// its final one and renamed, so a failed plot leaves no PNG behind (and an
// older one untouched). Returns "" on success, else a one-line message:
// gnuplot missing, the CSV unreadable or empty, a column missing, a cell not
// a finite number, gnuplot failing (with the first line it printed). Never
// throws for these; blocks until gnuplot exits.
std::string PlotCsv(const std::string& csv_path, const PlotSpec& spec);

}  // namespace uavsim::results
