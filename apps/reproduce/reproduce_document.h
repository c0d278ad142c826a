// The report of `uavsim reproduce` as a list of blocks, rendered to
// Markdown and HTML from the same blocks, and read back from the Markdown
// it rendered (so that a report can be redrawn in part).
#pragma once

#include <string>
#include <vector>

namespace uavsim::sim {

struct ReportBlock {
  enum Kind { kHeading, kText, kTable, kImage } kind = kText;
  std::string text;                            // heading, paragraph, image caption
  std::string file;                            // image: PNG beside the report
  std::vector<std::vector<std::string>> rows;  // table: header first
};

struct ReportDocument {
  std::vector<ReportBlock> blocks;
  void Heading(const std::string& t) { blocks.push_back({ReportBlock::kHeading, t, "", {}}); }
  void Text(const std::string& t) { blocks.push_back({ReportBlock::kText, t, "", {}}); }
  void Table(std::vector<std::vector<std::string>> rows) {
    blocks.push_back({ReportBlock::kTable, "", "", std::move(rows)});
  }
  void Image(const std::string& file, const std::string& caption) {
    blocks.push_back({ReportBlock::kImage, caption, file, {}});
  }
  // The index of the heading `text`, or blocks.size().
  std::size_t FindHeading(const std::string& text) const;
  // The index of the next heading after `i`, or blocks.size().
  std::size_t NextHeading(std::size_t i) const;
};

// "# title", then each block after a blank line: "## heading", the
// paragraph, "![caption](file)", or a table ("|" in cells as "\|").
std::string RenderMarkdown(const std::string& title, const ReportDocument& d);
// A page with the same blocks; a table cell beginning with a verdict gets
// its class: holds (green), does not hold / reversed (red), mixed (yellow),
// no effect (blue), not resolved (grey); `code` spans as <code>.
std::string RenderHtml(const std::string& title, const ReportDocument& d);
// The inverse of RenderMarkdown: RenderMarkdown(*title, result) == md for
// what RenderMarkdown wrote. Throws std::invalid_argument naming the line
// for anything else (no "# " title, a table row of another width).
ReportDocument ParseMarkdown(const std::string& md, std::string* title);

}  // namespace uavsim::sim
