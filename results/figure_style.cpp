#include "results/figure_style.h"

#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "results/gnuplot.h"
#include "results/gnuplot_figure.h"

namespace uavsim::results {
namespace {

constexpr int kLegendCharPx = 8;  // a character of a legend entry, roughly
constexpr int kLegendRowPx = 22;  // a row of the legend

}  // namespace

int Utf8Chars(const std::string& s) {
  int n = 0;
  for (char c : s) n += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
  return n;
}

std::vector<std::string> WrapWords(const std::string& text, int width) {
  std::vector<std::string> lines;
  std::istringstream words(text);
  for (std::string word; words >> word;) {
    if (!lines.empty() && Utf8Chars(lines.back()) + 1 + Utf8Chars(word) <= width)
      lines.back() += " " + word;
    else
      lines.push_back(word);
  }
  return lines;
}

// The newline goes in as a double-quoted "\n" between literal strings, the
// one escape gnuplot expands there.
std::string GnuplotLines(const std::vector<std::string>& lines) {
  std::string out;
  for (std::size_t i = 0; i < lines.size(); ++i)
    out += (i ? " . \"\\n\" . " : "") + GnuplotString(lines[i]);
  return out.empty() ? "''" : out;
}

LegendStrip SizeLegendStrip(int image_width_px, const std::vector<std::string>& entries,
                            int sample_px, int padding_px, bool titled) {
  int longest = 0;
  for (const auto& e : entries) longest = std::max(longest, Utf8Chars(e));
  const int entry_px = kLegendCharPx * longest + sample_px;
  const int count = static_cast<int>(entries.size());
  LegendStrip strip;
  strip.per_row = std::clamp((image_width_px - 40) / entry_px, 1, count);
  const int rows = (count + strip.per_row - 1) / strip.per_row;
  strip.height_px = padding_px + (titled ? kLegendRowPx : 0) + rows * kLegendRowPx;
  return strip;
}

void BeginMultiplot(GnuplotFigure& figure, bool titled) {
  figure.Commands() << "set multiplot" << (titled ? " title uavsim_title font ',14'" : "") << "\n"
                    << "unset key\n";
}

// The strip spans the image's width: screen 0 to 1 across.
void PlotLegendStrip(GnuplotFigure& figure, const ScreenCoordinates& screen, double top_px,
                     const std::string& unset_plot_texts, int sample_length,
                     const LegendStrip& strip, bool titled) {
  figure.PlotArea(screen, 0, screen.width_px, top_px, screen.height_px);
  figure.Commands() << unset_plot_texts
                    << "unset xlabel\nunset ylabel\nunset logscale\nunset grid\nunset border\n"
                    << "unset tics\nset xrange [0:1]\nset yrange [0:1]\n"
                    << "set key center center horizontal Left reverse samplen " << sample_length
                    << " spacing 1.1 width 1 maxcols " << strip.per_row
                    << (titled ? " title uavsim_key" : "") << "\n";
  figure.Plot();
  figure.Commands() << "unset multiplot\n";
}

}  // namespace uavsim::results
