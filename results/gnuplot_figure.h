// One gnuplot figure being built: the script results/ hands gnuplot for a
// PNG. The bar chart, the small multiples, the CSV line plot and the run
// report's figures all build theirs on it.
//
// Texts go in as variables holding gnuplot string expressions (GnuplotString,
// results/gnuplot.h: gnuplot performs no substitution in them), data as inline
// data blocks ($name << EOD), curves as the list of the next "plot" command.
// The script holds exactly what the calls write, in the order they are made:
// the same calls give the same script, byte for byte.
#pragma once

#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "results/gnuplot.h"

namespace uavsim::results {

// Pixel positions in an image as gnuplot screen coordinates ("at screen f":
// 0 at the left and bottom, 1 at the right and top), written shortest.
struct ScreenCoordinates {
  int width_px = 0;
  int height_px = 0;
  std::string X(double px_from_left) const;
  std::string Y(double px_from_top) const;
};

// How Plot() separates its curves.
enum class CurveLayout {
  kOnePerLine,  // ", \" and a new line indented under the first curve
  kOneLine,     // ", "
};

class GnuplotFigure {
 public:
  // The script so far, to append commands verbatim (each ending in "\n").
  std::ostream& Commands() { return script_; }

  // "variable = <text as a string expression>\n".
  void Text(const std::string& variable, const std::string& text);
  // The same for `lines` joined by newlines (GnuplotLines, "''" for none).
  void TextLines(const std::string& variable, const std::vector<std::string>& lines);
  // The inline data block "$name << EOD\n<rows>EOD\n"; `rows` end in "\n".
  void Data(const std::string& name, const std::string& rows);

  // Adds a curve (e.g. "$data using 1:2 with lines title v") to the next
  // "plot" command.
  void Curve(const std::string& curve);
  bool HasCurves() const { return !curves_.empty(); }
  // "plot <the curves added since the last plot>\n"; the list starts empty
  // again.
  void Plot(CurveLayout layout = CurveLayout::kOnePerLine);

  // The plot area by screen margins: "set lmargin at screen <left>\n", then
  // rmargin, tmargin and bmargin, from pixels of `screen`.
  void PlotArea(const ScreenCoordinates& screen, double left_px, double right_px, double top_px,
                double bottom_px);

  // Runs gnuplot on the script to draw `image`: RunGnuplot's contract ("" on
  // success, else one line saying why not; never throws for these).
  std::string Draw(const GnuplotImage& image) const;

 private:
  std::ostringstream script_;
  std::vector<std::string> curves_;
};

}  // namespace uavsim::results
