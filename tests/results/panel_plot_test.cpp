// The small-multiple plotter: the grid it chooses, the script it hands
// gnuplot (read back through a stand-in gnuplot that keeps it), a real
// drawing, and its one-line errors.
#include "results/panel_plot.h"

#include <catch2/catch.hpp>
#include <cstddef>
#include <filesystem>
#include <string>

#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::results::ChoosePanelGrid;
using uavsim::results::PanelPlotSpec;
using uavsim::results::PlotPanels;
using uavsim::testing::Between;
using uavsim::testing::Count;
using uavsim::testing::FakeGnuplot;
using uavsim::testing::PngSize;
using uavsim::testing::ReadFile;
using uavsim::testing::TempDir;
using uavsim::testing::WriteFile;

namespace {

// Two panels; in the first, series "a" (its rows out of x order, one y
// missing, one without an interval) and "b"; in the second "b" alone, and a
// series "c" that has no value anywhere.
const char* kTwoPanels =
    "x,y,ci95,series,panel\n"
    "3,4,,a,it's `A`\n"
    "1,2,0.5,a,it's `A`\n"
    "2,,,a,it's `A`\n"
    "1,3,,b,it's `A`\n"
    "1,5,,b,B\n"
    "2,6,,b,B\n"
    "1,,,c,B\n";

}  // namespace

TEST_CASE("ChoosePanelGrid: as few rows as allowed, columns balanced", "[results][panel_plot]") {
  const auto grid = [](int n, int most) {
    const auto g = ChoosePanelGrid(n, most);
    return std::to_string(g.columns) + "x" + std::to_string(g.rows);
  };
  CHECK(grid(0, 3) == "0x0");
  CHECK(grid(1, 3) == "1x1");
  CHECK(grid(2, 3) == "2x1");
  CHECK(grid(3, 3) == "3x1");
  CHECK(grid(4, 3) == "2x2");
  CHECK(grid(5, 3) == "3x2");
  CHECK(grid(7, 3) == "3x3");
  CHECK(grid(15, 3) == "3x5");
  CHECK(grid(5, 2) == "2x3");
  CHECK(grid(3, 0) == "1x3");  // at least one per row
}

TEST_CASE("PlotPanels: a panel per value, one colour per series, bands and a shared legend",
          "[results][panel_plot]") {
  const std::string dir = TempDir("panels-script");
  const std::string csv = dir + "/curves.csv", script = dir + "/script.gp";
  WriteFile(csv, kTwoPanels);
  PanelPlotSpec spec;
  spec.title = "RMSE vs loss";
  spec.x_label = "Loss";
  spec.y_label = "RMSE (m)";
  spec.legend_title = "method";
  spec.y_min_zero = true;
  spec.gnuplot = FakeGnuplot(dir, script);
  CHECK_THAT(PlotPanels(csv, spec), Catch::EndsWith("gnuplot wrote no image"));
  const std::string gp = ReadFile(script);

  // Panels in first-seen order, their names as literal strings.
  CHECK_THAT(gp, Catch::Contains("uavsim_panel0 = 'it'.\"'\".'s `A`'\n"));
  CHECK_THAT(gp, Catch::Contains("uavsim_panel1 = 'B'\n"));
  CHECK_THAT(gp, !Catch::Contains("uavsim_panel2"));
  // Per panel and series: x, y, band bottom and top; sorted by x, the
  // missing y left out, no interval = a band of no width.
  CHECK_THAT(gp, Catch::Contains("$p0s0 << EOD\n1 2 1.5 2.5\n3 4 4 4\nEOD\n"));
  CHECK_THAT(gp, Catch::Contains("$p0s1 << EOD\n1 3 3 3\nEOD\n"));
  CHECK_THAT(gp, Catch::Contains("$p1s1 << EOD\n1 5 5 5\n2 6 6 6\nEOD\n"));
  CHECK_THAT(gp, !Catch::Contains("$p1s0"));  // no "a" in panel B
  CHECK_THAT(gp, !Catch::Contains("$p1s2"));  // "c" has no value
  // A band where some interval is > 0, drawn before the lines.
  CHECK_THAT(gp, Catch::Contains("$p0s0 using 1:3:4 with filledcurves fc rgb '#1f77b4' notitle"));
  CHECK_THAT(gp, !Catch::Contains("$p0s1 using 1:3:4"));
  CHECK(gp.find("$p0s0 using 1:3:4") < gp.find("$p0s0 using 1:2"));
  // "b" has the same colour and marker in both panels.
  const std::string b_style = "using 1:2 with linespoints lc rgb '#ff7f0e' lw 2 pt 5";
  CHECK_THAT(gp, Catch::Contains("$p0s1 " + b_style));
  CHECK_THAT(gp, Catch::Contains("$p1s1 " + b_style));
  // The ranges are set once for every panel; y from 0, x with a margin.
  CHECK(Count(gp, "set yrange [") == 2);  // the panels', the legend's [0:1]
  CHECK_THAT(gp, Catch::Contains("set yrange [0:"));
  CHECK_THAT(gp, Catch::Contains("set xrange [0.92:3.08]\n"));
  CHECK(Count(gp, "\nplot ") == 3);  // two panels and the legend
  // One legend, in the strip below the panels: "a", "b" and the band, not
  // "c"; no legend in the panels.
  CHECK_THAT(gp, Catch::Contains("unset key\n"));
  CHECK(Count(gp, "set key ") == 1);
  CHECK_THAT(gp, Catch::Contains("set key center center horizontal"));
  CHECK_THAT(gp, Catch::Contains("title uavsim_key"));
  CHECK_THAT(gp, Catch::Contains("lc rgb '#1f77b4' lw 2 pt 7 ps 1.1 title uavsim_series0"));
  CHECK_THAT(gp, Catch::Contains("title uavsim_series1"));
  CHECK_THAT(gp, !Catch::Contains("title uavsim_series2"));
  CHECK_THAT(gp, Catch::Contains("title uavsim_band"));
  // The image grows with the panels: two side by side.
  CHECK_THAT(gp, Catch::Contains(" size 876,"));
  CHECK_THAT(gp, !Catch::Contains("\nset logscale"));
}

TEST_CASE("PlotPanels: the canvas grows with the panel count", "[results][panel_plot]") {
  const std::string dir = TempDir("panels-size");
  const std::string csv = dir + "/curves.csv", script = dir + "/script.gp";
  PanelPlotSpec spec;
  spec.gnuplot = FakeGnuplot(dir, script);
  std::string text = "x,y,ci95,series,panel\n";
  for (int k = 0; k < 5; ++k) text += "1,2,,s,p" + std::to_string(k) + "\n";
  WriteFile(csv, text);
  PlotPanels(csv, spec);
  const std::string five = Between(ReadFile(script), " size ", " ");
  WriteFile(csv, "x,y,ci95,series,panel\n1,2,,s,p\n");
  PlotPanels(csv, spec);
  const std::string one = Between(ReadFile(script), " size ", " ");
  // 3 columns x 2 rows against 1 x 1 (26 px gutter, 10 px edge).
  CHECK(five.substr(0, five.find(',')) == std::to_string(26 + 3 * 420 + 10));
  CHECK(one.substr(0, one.find(',')) == std::to_string(26 + 420 + 10));
  CHECK(std::stoi(five.substr(five.find(',') + 1)) - std::stoi(one.substr(one.find(',') + 1)) ==
        320);
}

TEST_CASE("PlotPanels: logarithmic axes, bands reaching 0 cut at the bottom, a cap on y",
          "[results][panel_plot]") {
  const std::string dir = TempDir("panels-log");
  const std::string csv = dir + "/curves.csv", script = dir + "/script.gp";
  PanelPlotSpec spec;
  spec.gnuplot = FakeGnuplot(dir, script);
  spec.log_x = spec.log_y = true;
  spec.y_min_zero = true;  // ignored on a log axis
  // 1 - 5 < 0: its band bottom is the axis's bottom.
  WriteFile(csv, "x,y,ci95,series,panel\n1,1,5,s,P\n10,100,1,s,P\n");
  PlotPanels(csv, spec);
  std::string gp = ReadFile(script);
  CHECK_THAT(gp, Catch::Contains("set logscale x\n"));
  CHECK_THAT(gp, Catch::Contains("set logscale y\n"));
  const std::string bottom = Between(gp, "set yrange [", ":");
  REQUIRE_FALSE(bottom.empty());
  CHECK(std::stod(bottom) > 0.0);
  CHECK(std::stod(bottom) < 1.0);
  CHECK_THAT(gp, Catch::Contains("$p0s0 << EOD\n1 1 " + bottom + " 6\n10 100 99 101\nEOD\n"));

  // Shares: the band above 1 is cut near 1, the point never.
  spec = PanelPlotSpec();
  spec.gnuplot = FakeGnuplot(dir, script);
  spec.y_min_zero = true;
  spec.y_max = 1.0;
  WriteFile(csv, "x,y,ci95,series,panel\n1,0.9,0.5,s,P\n2,0.5,0.1,s,P\n");
  PlotPanels(csv, spec);
  gp = ReadFile(script);
  const std::string range = Between(gp, "set yrange [", "]");
  CHECK(range.substr(0, 2) == "0:");
  CHECK(std::stod(range.substr(2)) == Approx(1.02));
}

TEST_CASE("PlotPanels: gnuplot draws the panels", "[results][panel_plot]") {
  const std::string dir = TempDir("panels-draw");
  const std::string csv = dir + "/curves.csv";
  WriteFile(csv, kTwoPanels);
  PanelPlotSpec spec;
  spec.title = "it's a \"figure\", `touch pwned`";
  spec.x_label = "Loss";
  spec.y_label = "RMSE (m)";
  spec.legend_title = "method";
  const std::string drawn = PlotPanels(csv, spec);
  if (drawn.find("gnuplot not found") != std::string::npos) {
    WARN("gnuplot is not installed: " << drawn);
    return;
  }
  CHECK(drawn == "");
  const auto [width, height] = PngSize(dir + "/curves.png");
  CHECK(width == 876);
  CHECK(height > 320);
  CHECK(fs::file_size(dir + "/curves.png") > 1000);
  CHECK_FALSE(fs::exists(fs::current_path() / "pwned"));
  CHECK_FALSE(fs::exists(dir + "/pwned"));
}

TEST_CASE("PlotPanels: problems are one line, and leave no image", "[results][panel_plot]") {
  const std::string dir = TempDir("panels-errors");
  const std::string csv = dir + "/curves.csv";
  PanelPlotSpec spec;
  const auto plot = [&](const std::string& text) {
    WriteFile(csv, text);
    return PlotPanels(csv, spec);
  };
  CHECK_THAT(PlotPanels(dir + "/absent.csv", spec), Catch::EndsWith("cannot read the file"));
  CHECK_THAT(plot(""), Catch::EndsWith("the file is empty"));
  CHECK_THAT(plot("x,y,ci95,series\n1,2,,a\n"), Catch::EndsWith("no column \"panel\""));
  CHECK_THAT(plot("x,y,series,panel\n1,2,a,p\n"), Catch::EndsWith("no column \"ci95\""));
  CHECK_THAT(plot("x,y,ci95,series,panel\n1,2,,a\n"),
             Catch::Contains("line 2 has 4 cells, the header 5"));
  CHECK_THAT(plot("x,y,ci95,series,panel\n1,2,,a,p\nabc,2,,a,p\n"),
             Catch::Contains("line 3: expected a finite number in \"x\""));
  CHECK_THAT(plot("x,y,ci95,series,panel\n1,nan,,a,p\n"),
             Catch::Contains("line 2: expected an empty cell or a finite number in \"y\""));
  CHECK_THAT(plot("x,y,ci95,series,panel\n1,2,-1,a,p\n"),
             Catch::Contains("line 2: expected an empty cell or a finite number >= 0 in \"ci95\""));
  CHECK_THAT(plot("x,y,ci95,series,panel\n"), Catch::EndsWith("no data rows"));
  CHECK_THAT(plot("x,y,ci95,series,panel\n1,,,a,p\n2,,0.5,b,q\n"), Catch::EndsWith("no data rows"));
  spec.log_x = true;
  CHECK_THAT(plot("x,y,ci95,series,panel\n0,2,,a,p\n"),
             Catch::Contains("line 2: x must be > 0 on a logarithmic axis"));
  spec.log_x = false;
  spec.log_y = true;
  CHECK_THAT(plot("x,y,ci95,series,panel\n1,-2,,a,p\n"),
             Catch::Contains("line 2: y must be > 0 on a logarithmic axis"));
  spec.log_y = false;
  std::string many = "x,y,ci95,series,panel\n";
  for (int k = 0; k < 100; ++k) many += "1,2,,a,p" + std::to_string(k) + "\n";
  CHECK_THAT(plot(many), Catch::Contains("the limit is 8192 pixels"));
  spec.panel_width_px = 10;
  CHECK_THAT(plot("x,y,ci95,series,panel\n1,2,,a,p\n"), Catch::Contains("at least 160 x 120"));
  spec = PanelPlotSpec();
  spec.gnuplot = dir + "/no-such-gnuplot";
  CHECK_THAT(plot("x,y,ci95,series,panel\n1,2,,a,p\n"), Catch::Contains("gnuplot not found"));
  CHECK_THAT(PlotPanels(csv, spec), Catch::StartsWith("panel plot " + csv + ": "));
  // No image, and no temporary one, left behind by any of them.
  for (const auto& e : fs::directory_iterator(dir)) CHECK(e.path().extension() != ".png");
  for (const auto& e : fs::directory_iterator(dir))
    CHECK(e.path().filename().string().find(".png.tmp") == std::string::npos);
}
