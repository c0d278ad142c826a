// `uavsim report DIR` on a reproduction (issue 48): the verdicts redrawn
// from claims.csv and the artefact tables alone, on a constructed folder
// (every outcome, the claim rules, the seeds needed, the margin) and on the
// shipped docs/paper reports, which must be what this binary redraws.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "apps/reproduce/reproduce_document.h"
#include "results/csv.h"
#include "results/sweep_report.h"
#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::testing::ReadFile;
using uavsim::testing::RunCli;
using uavsim::testing::TempDir;
using uavsim::testing::WriteFile;

namespace {

std::vector<std::vector<std::string>> Rows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream l(line);
    while (std::getline(l, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    rows.push_back(cells);
  }
  return rows;
}

// The text without the lines that contain `what`.
// `text` without the lines holding `what`, each with the blank line after
// it (a paragraph of Markdown).
std::string Without(const std::string& text, const std::string& what) {
  std::istringstream in(text);
  std::string line, out;
  bool dropped = false;
  while (std::getline(in, line)) {
    if (!(dropped && line.empty()) && line.find(what) == std::string::npos) out += line + "\n";
    dropped = line.find(what) != std::string::npos;
  }
  return out;
}

const char* kHeader =
    "artefact,claim,ours,verdict,detail,frame_split_verdict,comparison,diff_mean,diff_ci95,"
    "seeds,comparison_verdict\n";

// A reproduction folder of three claims as a three-outcome report wrote it.
std::string ConstructedFolder() {
  const std::string dir = TempDir("redraw");
  // Fig. 12's table: every RMSE 5 m, so its margin is 0.5 m.
  std::string fig12 = "subset,series,rmse_m,ci95,seeds\n";
  for (const char* s : {"TE-Align", "first"}) fig12 += std::string("all,") + s + ",5.0,1.0,3\n";
  WriteFile(dir + "/fig12_alignment.csv", fig12);
  WriteFile(dir + "/fig14_fusion_baselines.csv",
            "subset,series,rmse_m,ci95,seeds\nall,UAVLoc,10.0,1.0,3\nall,HeMIS,30.0,1.0,3\n");
  // 95 % half-widths t_{0.975,2} sd / sqrt 3 for sd 0.1, 0.05 and 2.
  const double t = uavsim::results::StudentT975(2);
  const auto hw = [&](double sd) { return uavsim::results::FormatFixed(t * sd / std::sqrt(3), 6); };
  const std::string a = "Fig. 12,TE-Align consistently outperforms the resampling methods,x,";
  const std::string b = "Fig. 14,UAVLoc outperforms all the considered baselines,y,";
  WriteFile(dir + "/claims.csv",
            std::string(kHeader) + a + "mixed,d,,a; 1,1.0," + hw(0.1) + ",3,holds\n" + a +
                "mixed,d,,a; 2,-1.0," + hw(0.1) + ",3,reversed\n" + a + "mixed,d,,a; 3,0.0," +
                hw(0.05) + ",3,within noise\n" + a + "mixed,d,,a; 4,1.0," + hw(2.0) +
                ",3,within noise\n" + b + "does not hold,d,,b; 1,1.0," + hw(2.0) +
                ",3,within noise\n" + b + "does not hold,d,,b; 2,-1.0," + hw(2.0) +
                ",3,within noise\n" +
                "Table III,The image encoder costs 147.32 MFLOPs,ratio 1.0001,holds,criterion: "
                "within 1 %; ok,,,,,,\n");
  WriteFile(dir + "/report.md",
            "# T\n\nScenario x.\n\nProtocol: 3 seeds. Verdicts compare methods (old rule).\n\n"
            "## Verdicts\n\nold counts\n\n"
            "| artefact | the paper says | uavsim (mean ± 95 % CI) | verdict | frame split |\n"
            "|---|---|---|---|---|\n"
            "| Fig. 12 | TE-Align consistently outperforms the resampling methods | x | mixed | - "
            "|\n| Fig. 14 | UAVLoc outperforms all the considered baselines | y | does not hold | "
            "- |\n| Table III | The image encoder costs 147.32 MFLOPs | ratio 1.0001 | holds: "
            "criterion: within 1 %, ok | - |\n\n"
            "## Fig. 12: time alignment\n\n![Fig. 12](fig12_alignment.png)\n\nkept as it was\n");
  return dir;
}

}  // namespace

TEST_CASE("Reproduce redraw: four outcomes, claim rules, margin and seeds from a folder",
          "[sim][reproduce]") {
  const std::string dir = ConstructedFolder();
  const auto r = RunCli({"report", dir, "--quiet"});
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const auto rows = Rows(ReadFile(dir + "/claims.csv"));
  REQUIRE(rows.size() == 8);
  REQUIRE(rows[0].size() == 15);
  CHECK(rows[0][11] == "split");
  CHECK(rows[0][14] == "seeds_needed");
  const std::vector<std::string> want = {"holds",        "reversed",     "no effect",
                                         "not resolved", "not resolved", "not resolved"};
  for (std::size_t i = 0; i < want.size(); ++i) {
    INFO(rows[i + 1][6]);
    CHECK(rows[i + 1][10] == want[i]);
    CHECK(rows[i + 1][11] == "trajectory");
  }
  // Margins: 10 % of the mean of the compared RMSE (5 m; 20 m).
  CHECK(std::stod(rows[1][13]) == Approx(0.5));
  CHECK(std::stod(rows[5][13]) == Approx(2.0));
  // Mean 1 (or -1), sd 2: 18 seeds (the hand computation of
  // reproduce_verdict_test); only where not resolved.
  CHECK(rows[4][14] == "18");
  CHECK(rows[5][14] == "18");
  CHECK(rows[1][14].empty());
  CHECK(rows[1][3] == "does not hold");  // one comparison reversed
  CHECK(rows[1][4] == "1 of 4 comparisons hold; 1 reversed; 1 no effect; 1 not resolved");
  CHECK(rows[5][3] == "not resolved");
  CHECK(rows[7][3] == "holds");  // a criterion: as it was
  CHECK(rows[7][6].empty());

  const std::string md = ReadFile(dir + "/report.md");
  CHECK(md.find("1 hold, 1 do not hold, 1 not resolved, 0 mixed") != std::string::npos);
  CHECK(md.find("| Fig. 14 | UAVLoc outperforms all the considered baselines | y | not resolved: "
                "0 of 2 comparisons hold, 2 not resolved | 18, 18 | - |") != std::string::npos);
  CHECK(md.find("holds: criterion: within 1 %, ok") != std::string::npos);  // the report's text
  CHECK(md.find("Protocol: 3 seeds. Verdicts compare methods seed by seed") != std::string::npos);
  CHECK(md.find("(old rule)") == std::string::npos);
  CHECK(md.find("Fig. 12 ±0.50 m, Fig. 14 ±2.00 m") != std::string::npos);
  CHECK(md.find("Verdicts redrawn by `uavsim report DIR`") != std::string::npos);
  CHECK(md.find("## Every comparison") != std::string::npos);
  CHECK(md.find("\n\nkept as it was\n") != std::string::npos);
  const std::string html = ReadFile(dir + "/report.html");
  for (const char* c : {"holds", "fails", "noeffect", "open"})
    CHECK(html.find(std::string("<td class=\"") + c + "\">") != std::string::npos);

  // Redrawn again: the same bytes.
  REQUIRE(RunCli({"report", dir, "--quiet"}).exit_code == 0);
  CHECK(ReadFile(dir + "/report.md") == md);
}

TEST_CASE("Reproduce redraw: bad tables refused with one line naming the file, exit 2",
          "[sim][reproduce]") {
  {
    const std::string dir = ConstructedFolder();
    const std::string csv = ReadFile(dir + "/claims.csv");
    WriteFile(dir + "/claims.csv",
              csv.substr(0, csv.find("1.0,")) + "x" + csv.substr(csv.find("1.0,") + 3));
    const auto r = RunCli({"report", dir});
    CHECK(r.exit_code == 2);
    CHECK(r.err.find(dir + "/claims.csv: line 2: diff_mean: expected a number, got 'x'") !=
          std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  }
  {
    const std::string dir = ConstructedFolder();
    fs::remove(dir + "/fig14_fusion_baselines.csv");
    const auto r = RunCli({"report", dir});
    CHECK(r.exit_code == 2);
    CHECK(r.err.find(dir + "/fig14_fusion_baselines.csv: cannot read the file") !=
          std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  }
  {
    const std::string dir = ConstructedFolder();
    const std::string md = ReadFile(dir + "/report.md");
    WriteFile(dir + "/report.md", md.substr(0, md.find("| Table III")));
    const auto r = RunCli({"report", dir});
    CHECK(r.exit_code == 2);
    CHECK(r.err.find(dir + "/report.md: the verdict table has 2 claims, claims.csv 3") !=
          std::string::npos);
  }
}

TEST_CASE("Reproduce redraw: the shipped reports are what this binary redraws",
          "[sim][reproduce]") {
  for (const char* name : {"city", "twin"}) {
    INFO(name);
    const std::string shipped = std::string(UAVSIM_SOURCE_DIR) + "/docs/paper/" + name;
    const std::string dir = TempDir(std::string("redraw-") + name);
    fs::copy(shipped, dir, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
    // The Markdown reads back into the blocks it was rendered from.
    std::string title;
    const std::string md = ReadFile(shipped + "/report.md");
    CHECK(uavsim::sim::RenderMarkdown(title, uavsim::sim::ParseMarkdown(md, &title)) == md);

    const auto r = RunCli({"report", dir, "--quiet"});
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    CHECK(ReadFile(dir + "/claims.csv") == ReadFile(shipped + "/claims.csv"));
    // The same but for the binary's version in the redraw's note.
    CHECK(Without(ReadFile(dir + "/report.md"), "Verdicts redrawn") ==
          Without(md, "Verdicts redrawn"));
    CHECK(Without(ReadFile(dir + "/report.html"), "Verdicts redrawn") ==
          Without(ReadFile(shipped + "/report.html"), "Verdicts redrawn"));

    // Each comparison's verdict follows from its own row by the rules, and
    // Fig. 7's margin is 10 % of the mean of fig07's RMSE column.
    const auto rows = Rows(ReadFile(dir + "/claims.csv"));
    double sum = 0.0;
    int n = 0;
    for (const auto& row : Rows(ReadFile(dir + "/fig07_camera_z.csv")))
      if (row[2] != "rmse_m") sum += std::stod(row[2]), ++n;
    std::size_t checked = 0;
    for (std::size_t i = 1; i < rows.size(); ++i) {
      const auto& c = rows[i];
      if (c[6].empty()) continue;
      INFO(c[0] << ": " << c[6]);
      const double mean = std::stod(c[7]), hw = std::stod(c[8]), margin = std::stod(c[13]);
      const int seeds = std::stoi(c[9]);
      REQUIRE(seeds == 3);
      const double ci90 = hw * uavsim::results::StudentTQuantile(2, 0.95) / 4.302652730;
      CHECK(std::stod(c[12]) == Approx(ci90).margin(2e-6));
      const std::string v = mean - hw > 0                                   ? "holds"
                            : mean + hw < 0                                 ? "reversed"
                            : mean - ci90 > -margin && mean + ci90 < margin ? "no effect"
                                                                            : "not resolved";
      CHECK(c[10] == v);
      CHECK(c[14].empty() == (v != "not resolved"));
      if (c[0] == "Fig. 7") CHECK(margin == Approx(0.1 * sum / n).margin(1e-6));
      ++checked;
    }
    CHECK(checked > 100);
  }
}
