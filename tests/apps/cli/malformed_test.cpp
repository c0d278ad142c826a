// The malformed-scenario battery: every file in tests/malformed/ is wrong in
// exactly one way, and expected.tsv says where `uavsim validate` must point
// and what it must say (FILENAME<TAB>POINTER<TAB>SUBSTRING; POINTER is a JSON
// pointer, "line L, column C" for syntax errors, or "-" for none).
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "test_support.h"

namespace {

namespace fs = std::filesystem;
using uavsim::testing::RunCli;
using uavsim::testing::TempDir;

struct Expectation {
  std::string file;
  std::string pointer;
  std::string substring;
};

fs::path BatteryDir() { return fs::path(UAVSIM_SOURCE_DIR) / "tests" / "malformed"; }

std::vector<std::string> SplitTabs(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t tab = line.find('\t', start);
    fields.push_back(
        line.substr(start, tab == std::string::npos ? std::string::npos : tab - start));
    if (tab == std::string::npos) return fields;
    start = tab + 1;
  }
}

// Parsed once; a malformed row throws, naming its line.
const std::vector<Expectation>& Battery() {
  static const std::vector<Expectation> rows = [] {
    const fs::path tsv = BatteryDir() / "expected.tsv";
    std::ifstream in(tsv);
    if (!in) throw std::runtime_error("cannot read " + tsv.string());
    std::vector<Expectation> out;
    std::string line;
    int line_no = 0;
    while (std::getline(in, line)) {
      ++line_no;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.empty() || line[0] == '#') continue;
      const std::vector<std::string> f = SplitTabs(line);
      if (f.size() != 3 || f[0].empty() || f[1].empty() || f[2].empty())
        throw std::runtime_error("expected.tsv line " + std::to_string(line_no) +
                                 ": expected FILENAME<TAB>POINTER<TAB>SUBSTRING, got: " + line);
      out.push_back({f[0], f[1], f[2]});
    }
    return out;
  }();
  return rows;
}

std::set<std::string> JsonFilesInBattery() {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(BatteryDir()))
    if (entry.is_regular_file() && entry.path().extension() == ".json")
      names.insert(entry.path().filename().string());
  return names;
}

// Everything directly under `dir`, hidden entries included.
std::vector<std::string> Entries(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    names.push_back(entry.path().filename().string());
  return names;
}

}  // namespace

TEST_CASE("Malformed battery: expected.tsv and the folder list the same files", "[sim]") {
  const std::vector<Expectation>& rows = Battery();
  CHECK(rows.size() >= 40);

  std::set<std::string> listed;
  for (const Expectation& row : rows) {
    INFO("row " << row.file);
    CHECK(listed.insert(row.file).second);  // one row per file
  }
  const std::set<std::string> on_disk = JsonFilesInBattery();
  for (const std::string& name : on_disk) {
    INFO(name << " is in tests/malformed/ but has no row in expected.tsv");
    CHECK(listed.count(name) == 1);
  }
  for (const std::string& name : listed) {
    INFO(name << " has a row in expected.tsv but is not in tests/malformed/");
    CHECK(on_disk.count(name) == 1);
  }
}

// Checks one file's line of `uavsim validate` stderr against its row.
void CheckLine(const Expectation& row, const std::string& path, const std::string& line) {
  const std::string prefix =
      path + ": " + (row.pointer == "-" ? std::string() : row.pointer + ": ");
  INFO("expected prefix: " << prefix);
  INFO("expected substring: " << row.substring);
  INFO("line: " << line);
  CHECK(line.compare(0, prefix.size(), prefix) == 0);
  // The substring belongs to the message, after the location.
  const std::string message = line.size() > prefix.size() ? line.substr(prefix.size()) : "";
  CHECK(message.find(row.substring) != std::string::npos);
}

std::string BatteryPath(const Expectation& row) {
  return fs::absolute(BatteryDir() / row.file).lexically_normal().string();
}

TEST_CASE("Malformed battery: validate exits 2 with one line naming file, pointer and fault",
          "[sim][slow]") {
  // Every file in one `uavsim validate` (a process start costs about a
  // second of LibTorch loading): one line per file, in order.
  std::vector<std::string> args{"validate"};
  for (const Expectation& row : Battery()) args.push_back(BatteryPath(row));
  const auto all = RunCli(args);
  INFO("stderr: " << all.err);
  CHECK(all.exit_code == 2);
  CHECK(all.out.empty());
  REQUIRE(!all.err.empty());
  CHECK(all.err.back() == '\n');
  std::vector<std::string> lines;
  std::istringstream in(all.err);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  REQUIRE(lines.size() == Battery().size());
  for (std::size_t i = 0; i < lines.size(); ++i) {
    INFO("file: " << Battery()[i].file);
    CheckLine(Battery()[i], BatteryPath(Battery()[i]), lines[i]);
  }
  // And alone, as a user gives one file: exit 2 and exactly one line (every
  // seventh row, which covers each kind of fault in the list's order).
  for (std::size_t i = 0; i < Battery().size(); i += 7) {
    const Expectation& row = Battery()[i];
    INFO("alone: " << row.file);
    const auto r = RunCli({"validate", BatteryPath(row)});
    INFO("stderr: " << r.err);
    CHECK(r.exit_code == 2);
    CHECK(r.out.empty());
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    if (!r.err.empty() && r.err.back() == '\n')
      CheckLine(row, BatteryPath(row), r.err.substr(0, r.err.size() - 1));
    else
      FAIL_CHECK("stderr does not end with a newline");
  }
}

TEST_CASE("Malformed battery: run refuses before writing anything", "[sim][slow]") {
  // One of each family: syntax, unknown key, cross-reference, resource guard.
  const std::vector<std::string> files = {"syntax_truncated.json", "unknown_key_top_typo.json",
                                          "duplicate_node_ids.json", "uplink_dangling.json",
                                          "resource_camera_rays_per_second.json"};
  for (const std::string& name : files) {
    DYNAMIC_SECTION(name) {
      const std::string path = fs::absolute(BatteryDir() / name).lexically_normal().string();
      REQUIRE(fs::is_regular_file(path));
      const std::string tmp = TempDir("malformed-run");
      const std::string out = tmp + "/run";
      const auto r = RunCli({"run", path, "--out", out, "--quiet"}, tmp);
      INFO("stderr: " << r.err);
      CHECK(r.exit_code == 2);
      CHECK(r.err.compare(0, path.size() + 2, path + ": ") == 0);
      CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
      CHECK_FALSE(fs::exists(out));
      // No staging folder, temporary file or default runs/ folder either.
      std::string left;
      for (const std::string& e : Entries(tmp)) left += " " + e;
      INFO("left behind beside --out:" << left);
      CHECK(left.empty());
    }
  }
}
