// What the figures of results/ share, so that they look alike side by side:
// the colours of their series, the measuring and wrapping of their texts, and
// the frame of a multiplot with its legend in a strip below the plots. Used
// by panel_plot.cpp and bar_plot.cpp; not a plotting interface.
#pragma once

#include <string>
#include <vector>

#include "results/gnuplot_figure.h"

namespace uavsim::results {

// Tableau 10, the colour of series number i being kSeriesColours[i % 10].
inline constexpr const char* kSeriesColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                                 "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                                                 "#bcbd22", "#17becf"};
inline constexpr int kSeriesColourCount = 10;

// Characters of UTF-8 text (continuation bytes not counted).
int Utf8Chars(const std::string& s);

// `text` broken at spaces into lines of at most `width` characters (a
// longer word keeps a line of its own); "" gives no line.
std::vector<std::string> WrapWords(const std::string& text, int width);

// A gnuplot string expression of `lines` joined by newlines ("''" for none).
std::string GnuplotLines(const std::vector<std::string>& lines);

// The legend strip below a multiplot's plots: its entries in rows.
struct LegendStrip {
  int per_row = 1;    // entries in a row
  int height_px = 0;  // the strip's height
};

// The strip for the texts of `entries` (at least one) in an image
// `image_width_px` wide: each entry as wide as the longest text (8 px a
// character) plus `sample_px` for its sample, as many to a row as fit in the
// width less 40 px (at least one); rows of 22 px, one more for the legend's
// title when `titled`, and `padding_px` besides. Integer pixels.
LegendStrip SizeLegendStrip(int image_width_px, const std::vector<std::string>& entries,
                            int sample_px, int padding_px, bool titled);

// Starts a multiplot: "set multiplot", with the figure's title (variable
// uavsim_title, sans 14) when `titled`; the plots draw no key.
void BeginMultiplot(GnuplotFigure& figure, bool titled);

// Ends the multiplot with its legend: the curves added to `figure` (undefined
// ones, "NaN with ... title ...") plotted into the strip from `top_px` down to
// the image's bottom, once `unset_plot_texts` (commands, e.g. "unset title\n")
// and the axes, labels, scales, grid, border and tics of the plots are turned
// off. Samples `sample_length` characters long; the legend's title is
// uavsim_key when `titled`.
void PlotLegendStrip(GnuplotFigure& figure, const ScreenCoordinates& screen, double top_px,
                     const std::string& unset_plot_texts, int sample_length,
                     const LegendStrip& strip, bool titled);

}  // namespace uavsim::results
