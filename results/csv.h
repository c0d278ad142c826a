// A CSV table built in memory with fixed, locale-independent number
// formatting, so the same values always give the same bytes.
#pragma once

#include <initializer_list>
#include <string>
#include <vector>

namespace uavsim::results {

// The cells of one line of a plain CSV (no quoting): split at every comma,
// so "a,,b," has four cells and "" one.
std::vector<std::string> SplitCsvLine(const std::string& line);

// Fixed-point with `decimals` digits; "-0.000" is printed as "0.000".
std::string FormatFixed(double x, int decimals);

class CsvTable {
 public:
  explicit CsvTable(std::vector<std::string> columns);
  // One row; cells already formatted. Throws if the count differs.
  void AddRow(const std::vector<std::string>& cells);
  std::size_t rows() const { return rows_; }
  const std::string& str() const { return text_; }

 private:
  std::size_t columns_;
  std::size_t rows_ = 0;
  std::string text_;
};

}  // namespace uavsim::results
