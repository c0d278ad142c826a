#include "results/html.h"

#include <charconv>
#include <cmath>

namespace uavsim::results {
namespace {

bool LooksNumeric(const std::string& s) {
  if (s.empty()) return false;
  // "0.12 ± 0.03": a mean and its interval.
  if (const auto pm = s.find(" \u00b1 "); pm != std::string::npos)
    return LooksNumeric(s.substr(0, pm)) && LooksNumeric(s.substr(pm + 4));
  double x = 0.0;
  const char* begin = s.data();
  const char* end = s.data() + s.size();
  if (*begin == '+') ++begin;
  const auto r = std::from_chars(begin, end, x);
  // "12.5 %" and "3.1x" read as numbers too: a short unit after the number.
  return r.ec == std::errc() && (r.ptr == end || (end - r.ptr <= 3 && *r.ptr == ' ') ||
                                 (end - r.ptr == 1 && (*r.ptr == 'x' || *r.ptr == '%')));
}

constexpr const char* kStyle = R"(
body { font-family: sans-serif; margin: 1.5em auto; max-width: 1280px; padding: 0 1em;
       color: #222; line-height: 1.4; }
h1 { font-size: 1.6em; border-bottom: 2px solid #888; padding-bottom: .2em; }
h2 { font-size: 1.25em; margin-top: 1.6em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; margin: .6em 0; font-size: .92em; }
th, td { border: 1px solid #ccc; padding: .25em .6em; }
th { background: #eee; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
figure { margin: .6em 0; display: inline-block; vertical-align: top; max-width: 100%; }
figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: .9em; color: #444; max-width: 900px; }
.row { display: flex; flex-wrap: wrap; gap: 1em; }
.row figure { flex: 1 1 560px; }
.missing { color: #a00; }
)";

}  // namespace

std::string HtmlEscape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default: {
        const auto u = static_cast<unsigned char>(c);
        out += (u < 0x20 && c != '\t' && c != '\n') || u == 0x7f ? ' ' : c;
      }
    }
  }
  return out;
}

std::string HtmlLink(const std::string& href, const std::string& text) {
  return "<a href=\"" + HtmlEscape(href) + "\">" + HtmlEscape(text) + "</a>";
}

HtmlPage::HtmlPage(const std::string& title) : title_(title) {
  body_ += "<h1>" + HtmlEscape(title) + "</h1>\n";
}

void HtmlPage::Heading(const std::string& text) { body_ += "<h2>" + HtmlEscape(text) + "</h2>\n"; }

void HtmlPage::Paragraph(const std::string& text) { body_ += "<p>" + HtmlEscape(text) + "</p>\n"; }

void HtmlPage::RawParagraph(const std::string& html) { body_ += "<p>" + html + "</p>\n"; }

void HtmlPage::Table(const std::vector<std::vector<std::string>>& rows) {
  if (rows.empty()) return;
  body_ += "<table>\n<tr>";
  for (const auto& h : rows.front()) body_ += "<th>" + HtmlEscape(h) + "</th>";
  body_ += "</tr>\n";
  for (std::size_t r = 1; r < rows.size(); ++r) {
    body_ += "<tr>";
    for (const auto& c : rows[r])
      body_ += (LooksNumeric(c) ? "<td class=\"num\">" : "<td>") + HtmlEscape(c) + "</td>";
    body_ += "</tr>\n";
  }
  body_ += "</table>\n";
}

void HtmlPage::Figure(const std::string& relative_png, const std::string& caption,
                      const std::string& missing) {
  body_ += "<figure>";
  if (missing.empty()) {
    images_.push_back(relative_png);
    body_ += "<img src=\"" + HtmlEscape(relative_png) + "\" alt=\"" + HtmlEscape(caption) + "\">";
  } else {
    body_ += "<p class=\"missing\">Not drawn: " + HtmlEscape(missing) + "</p>";
  }
  body_ += "<figcaption>" + HtmlEscape(caption) + "</figcaption></figure>\n";
}

void HtmlPage::BeginRow() { body_ += "<div class=\"row\">\n"; }
void HtmlPage::EndRow() { body_ += "</div>\n"; }

std::string HtmlPage::str() const {
  return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" +
         HtmlEscape(title_) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n" + body_ +
         "</body>\n</html>\n";
}

}  // namespace uavsim::results
