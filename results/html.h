// The few pieces of HTML the reports are made of: one self-contained page
// (inline CSS, no script, no network access), headings, tables and figures
// that reference PNGs by relative path, so a report opens from disk.
#pragma once

#include <string>
#include <vector>

namespace uavsim::results {

// `s` with &, <, >, " and ' as entities (safe in text and in attribute
// values); control characters other than tab and newline become spaces.
std::string HtmlEscape(const std::string& s);

// <a href="href">text</a>, both escaped: a link for RawParagraph.
std::string HtmlLink(const std::string& href, const std::string& text);

class HtmlPage {
 public:
  explicit HtmlPage(const std::string& title);  // also the page's <h1>

  void Heading(const std::string& text);    // <h2>
  void Paragraph(const std::string& text);  // escaped text
  // A paragraph of raw HTML (the caller escapes what it interpolates).
  void RawParagraph(const std::string& html);
  // A table: the first row is the header. Cells are escaped; a cell whose
  // text parses as a number (or "number ± number") is right-aligned.
  void Table(const std::vector<std::vector<std::string>>& rows);
  // An image by relative path, with alt text and a caption; `missing` set:
  // a note that the plot could not be drawn (and why) instead.
  void Figure(const std::string& relative_png, const std::string& caption,
              const std::string& missing = "");
  // Figures side by side (wrapping on narrow windows).
  void BeginRow();
  void EndRow();

  std::string str() const;  // the whole page, closed
  // The relative paths of every image the page shows, in order.
  const std::vector<std::string>& images() const { return images_; }

 private:
  std::string body_;
  std::string title_;
  std::vector<std::string> images_;
};

}  // namespace uavsim::results
