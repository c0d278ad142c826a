#include "apps/reproduce/reproduce_document.h"

#include <sstream>
#include <stdexcept>

#include "results/html.h"

namespace uavsim::sim {
namespace {

std::string MdCell(const std::string& s) {
  std::string out;
  for (char c : s) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

// Inline `code` spans of a paragraph as <code>.
std::string HtmlText(const std::string& s) {
  std::string out;
  bool code = false;
  std::string run;
  for (char c : s) {
    if (c == '`') {
      out += results::HtmlEscape(run);
      run.clear();
      out += code ? "</code>" : "<code>";
      code = !code;
    } else {
      run += c;
    }
  }
  out += results::HtmlEscape(run);
  if (code) out += "</code>";
  return out;
}

std::string VerdictClass(const std::string& cell) {
  const auto starts = [&](const char* p) { return cell.rfind(p, 0) == 0; };
  if (starts("holds")) return " class=\"holds\"";
  if (starts("does not hold") || starts("reversed")) return " class=\"fails\"";
  if (starts("mixed")) return " class=\"mixed\"";
  if (starts("no effect")) return " class=\"noeffect\"";
  if (starts("not resolved")) return " class=\"open\"";
  return "";
}

// The cells of a rendered table row "| a | b \| c |".
std::vector<std::string> TableCells(const std::string& line, std::size_t line_no) {
  std::vector<std::string> cells;
  std::string cell;
  bool first = true;
  for (std::size_t i = 1; i < line.size(); ++i) {
    if (line[i] == '\\' && i + 1 < line.size() && line[i + 1] == '|') {
      cell += '|', ++i;
    } else if (line[i] == '|') {
      if (cell.size() < 2 || cell.front() != ' ' || cell.back() != ' ')
        throw std::invalid_argument("line " + std::to_string(line_no) + ": not a table row");
      cells.push_back(cell.substr(1, cell.size() - 2));
      cell.clear();
    } else {
      cell += line[i];
    }
    first = false;
  }
  if (first || !cell.empty())
    throw std::invalid_argument("line " + std::to_string(line_no) + ": not a table row");
  return cells;
}

}  // namespace

std::size_t ReportDocument::FindHeading(const std::string& text) const {
  for (std::size_t i = 0; i < blocks.size(); ++i)
    if (blocks[i].kind == ReportBlock::kHeading && blocks[i].text == text) return i;
  return blocks.size();
}

std::size_t ReportDocument::NextHeading(std::size_t i) const {
  for (++i; i < blocks.size(); ++i)
    if (blocks[i].kind == ReportBlock::kHeading) return i;
  return blocks.size();
}

std::string RenderMarkdown(const std::string& title, const ReportDocument& d) {
  std::ostringstream md;
  md << "# " << title << "\n";
  for (const ReportBlock& b : d.blocks) {
    md << "\n";
    switch (b.kind) {
      case ReportBlock::kHeading:
        md << "## " << b.text << "\n";
        break;
      case ReportBlock::kText:
        md << b.text << "\n";
        break;
      case ReportBlock::kImage:
        md << "![" << b.text << "](" << b.file << ")\n";
        break;
      case ReportBlock::kTable:
        for (std::size_t r = 0; r < b.rows.size(); ++r) {
          md << "|";
          for (const std::string& c : b.rows[r]) md << " " << MdCell(c) << " |";
          md << "\n";
          if (r == 0) {
            md << "|";
            for (std::size_t c = 0; c < b.rows[0].size(); ++c) md << "---|";
            md << "\n";
          }
        }
        break;
    }
  }
  return md.str();
}

std::string RenderHtml(const std::string& title, const ReportDocument& d) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>"
    << results::HtmlEscape(title)
    << "</title>\n<style>\n"
       "body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;"
       "color:#222;line-height:1.45}\n"
       "table{border-collapse:collapse;margin:1em 0;font-size:0.92em}\n"
       "td,th{border:1px solid #ccc;padding:0.25em 0.6em;vertical-align:top}\n"
       "th{background:#f2f2f2}\n"
       "td.holds{background:#dff0d8}td.fails{background:#f2dede}td.mixed{background:#fcf8e3}\n"
       "td.noeffect{background:#d9e6f5}td.open{background:#e6e6e6}\n"
       "img{max-width:100%;border:1px solid #ddd;margin:0.5em 0}\n"
       "code{background:#f5f5f5;padding:0 0.2em}\n"
       "</style></head><body>\n<h1>"
    << results::HtmlEscape(title) << "</h1>\n";
  for (const ReportBlock& b : d.blocks) {
    switch (b.kind) {
      case ReportBlock::kHeading:
        h << "<h2>" << results::HtmlEscape(b.text) << "</h2>\n";
        break;
      case ReportBlock::kText:
        h << "<p>" << HtmlText(b.text) << "</p>\n";
        break;
      case ReportBlock::kImage:
        h << "<figure><img src=\"" << results::HtmlEscape(b.file) << "\" alt=\""
          << results::HtmlEscape(b.text) << "\"><figcaption>" << results::HtmlEscape(b.text)
          << "</figcaption></figure>\n";
        break;
      case ReportBlock::kTable:
        h << "<table>\n";
        for (std::size_t r = 0; r < b.rows.size(); ++r) {
          h << "<tr>";
          for (const std::string& c : b.rows[r]) {
            if (r == 0)
              h << "<th>" << results::HtmlEscape(c) << "</th>";
            else
              h << "<td" << VerdictClass(c) << ">" << HtmlText(c) << "</td>";
          }
          h << "</tr>\n";
        }
        h << "</table>\n";
        break;
    }
  }
  h << "</body></html>\n";
  return h.str();
}

ReportDocument ParseMarkdown(const std::string& md, std::string* title) {
  std::vector<std::string> lines;
  {
    std::istringstream in(md);
    std::string line;
    while (std::getline(in, line)) lines.push_back(line);
  }
  if (lines.empty() || lines[0].rfind("# ", 0) != 0)
    throw std::invalid_argument("line 1: expected the title (\"# ...\")");
  if (title) *title = lines[0].substr(2);
  ReportDocument d;
  for (std::size_t i = 1; i < lines.size();) {
    if (!lines[i].empty() || i + 1 >= lines.size())
      throw std::invalid_argument("line " + std::to_string(i + 1) + ": expected a blank line");
    ++i;  // the blank line before every block
    const std::string& l = lines[i];
    const std::size_t at = i + 1;  // 1-based line number
    if (l.rfind("## ", 0) == 0) {
      d.Heading(l.substr(3));
      ++i;
    } else if (l.rfind("![", 0) == 0 && l.back() == ')' && l.find("](") != std::string::npos) {
      const std::size_t mid = l.rfind("](");
      d.Image(l.substr(mid + 2, l.size() - mid - 3), l.substr(2, mid - 2));
      ++i;
    } else if (l.rfind("|", 0) == 0) {
      std::vector<std::vector<std::string>> rows{TableCells(l, at)};
      if (i + 1 >= lines.size() || lines[i + 1].rfind("|---|", 0) != 0)
        throw std::invalid_argument("line " + std::to_string(at + 1) + ": expected |---|");
      for (i += 2; i < lines.size() && lines[i].rfind("|", 0) == 0; ++i) {
        rows.push_back(TableCells(lines[i], i + 1));
        if (rows.back().size() != rows[0].size())
          throw std::invalid_argument("line " + std::to_string(i + 1) + ": " +
                                      std::to_string(rows.back().size()) + " cells, the header " +
                                      std::to_string(rows[0].size()));
      }
      d.Table(std::move(rows));
    } else {
      d.Text(l);
      ++i;
    }
  }
  return d;
}

}  // namespace uavsim::sim
