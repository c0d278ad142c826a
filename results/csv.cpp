#include "results/csv.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace uavsim::results {

std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> cells(1);
  for (char c : line) {
    if (c == ',')
      cells.emplace_back();
    else
      cells.back() += c;
  }
  return cells;
}

long CsvFile::Column(const std::string& name) const {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<long>(i);
  return -1;
}

std::string ReadCsvFile(const std::string& path, CsvFile* out) {
  *out = CsvFile{};
  std::ifstream in(path, std::ios::binary);
  if (!in) return "cannot read the file";
  std::string line;
  if (!std::getline(in, line)) return "the file is empty";
  if (!line.empty() && line.back() == '\r') line.pop_back();
  out->header = SplitCsvLine(line);
  for (std::size_t number = 2; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    std::vector<std::string> cells = SplitCsvLine(line);
    if (cells.size() != out->header.size())
      return "line " + std::to_string(number) + " has " + std::to_string(cells.size()) +
             " cells, the header " + std::to_string(out->header.size());
    out->rows.push_back(std::move(cells));
    out->line.push_back(number);
  }
  return "";
}

std::string FormatFixed(double x, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, x);
  std::string s(buf);
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

CsvTable::CsvTable(std::vector<std::string> columns) : columns_(columns.size()) {
  AddRow(columns);
  rows_ = 0;
}

void CsvTable::AddRow(const std::vector<std::string>& cells) {
  if (cells.size() != columns_)
    throw std::logic_error("CsvTable: row has the wrong number of cells");
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (i) text_ += ',';
    text_ += cells[i];
  }
  text_ += '\n';
  ++rows_;
}

}  // namespace uavsim::results
