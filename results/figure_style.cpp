#include "results/figure_style.h"

#include <sstream>
#include <string>
#include <vector>

#include "results/gnuplot.h"

namespace uavsim::results {

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

}  // namespace uavsim::results
