// Running gnuplot on a script we write: the one place that starts gnuplot
// (results/gnuplot_figure.h builds the scripts of results/ on it).
//
// Texts go into scripts as gnuplot string expressions (GnuplotString) in
// which gnuplot performs no substitution; data go in as inline data blocks
// ($name << EOD). gnuplot runs without a shell, stdin from /dev/null, on a
// script in a temporary file. The PNG is written under a temporary name
// beside its final one and renamed, so a failed plot leaves no PNG behind
// (and an older one untouched).
#pragma once

#include <string>

namespace uavsim::results {

// A gnuplot string expression that evaluates to `s` exactly, up to control
// characters, which become spaces (a newline would end the command).
std::string GnuplotString(const std::string& s);

// The shortest text that reads back as `x` (locale-independent).
std::string ShortestNumber(double x);

// A finite number filling all of `s`.
bool ParseFiniteNumber(const std::string& s, double* x);

struct GnuplotImage {
  std::string png_path;
  int width_px = 800;               // 64 .. 8192
  int height_px = 560;              // 64 .. 8192
  std::string font = "sans,10";     // "" = the terminal's default
  std::string gnuplot = "gnuplot";  // the program; searched on PATH unless it contains '/'
};

// Runs `script` (everything after the terminal and output are set: it must
// not set them itself) to draw `image`. The terminal is pngcairo when
// gnuplot has it, else png. Returns "" on success, else a one-line message
// (gnuplot missing, failing with the first line it printed, writing no
// image). Never throws for these; blocks until gnuplot exits.
std::string RunGnuplot(const std::string& script, const GnuplotImage& image);

}  // namespace uavsim::results
