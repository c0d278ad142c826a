// What the figures of results/ share, so that they look alike side by side:
// the colours of their series and the measuring and wrapping of their texts.
// Used by panel_plot.cpp and bar_plot.cpp; not a plotting interface.
#pragma once

#include <string>
#include <vector>

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

}  // namespace uavsim::results
