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

// A plain CSV file read whole: its header's cells and each non-empty
// line's cells (a trailing '\r' dropped), every row as wide as the header.
struct CsvFile {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::vector<std::size_t> line;  // each row's line number in the file (the header's is 1)
  long Column(const std::string& name) const;  // its index, or -1
};

// Reads `path` into *out. Returns "" on success, else why not: "cannot read
// the file", "the file is empty", "line N has K cells, the header H".
std::string ReadCsvFile(const std::string& path, CsvFile* out);

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
