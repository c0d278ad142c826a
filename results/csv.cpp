#include "results/csv.h"

#include <cmath>
#include <cstdio>
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
