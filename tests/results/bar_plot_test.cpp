// The grouped bar chart: the script it hands gnuplot (read back through a
// stand-in gnuplot that keeps it), a real drawing, and its one-line errors.
#include "results/bar_plot.h"

#include <catch2/catch.hpp>
#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>

#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::results::BarPlotSpec;
using uavsim::results::PlotBars;
using uavsim::testing::Between;
using uavsim::testing::Count;
using uavsim::testing::FakeGnuplot;
using uavsim::testing::PngSize;
using uavsim::testing::ReadFile;
using uavsim::testing::TempDir;
using uavsim::testing::WriteFile;

namespace {

// Three categories (the first with a quote and backquotes in its name), the
// rows out of order; series "a" has no bar in "B" (its interval there is
// ignored) and no interval in "C"; series "c" has no bar anywhere.
const char* kGroups =
    "category,series,y,ci95\n"
    "it's `A`,a,2,0.5\n"
    "it's `A`,b,3,\n"
    "B,b,5,0.25\n"
    "B,a,,0.1\n"
    "C,a,4,\n"
    "C,c,,\n"
    "C,b,6,1\n";

// Seven modality combinations x five methods, some intervals, one bar
// missing: the figure the reports draw.
std::string ModalityTable() {
  const char* categories[] = {"camera",
                              "lidar",
                              "radar",
                              "camera+lidar",
                              "camera+radar",
                              "lidar+radar",
                              "camera+lidar+radar"};
  const char* methods[] = {"Mamba", "GRU", "LSTM", "Transformer", "Kalman filter"};
  std::string text = "category,series,y,ci95\n";
  for (int k = 0; k < 7; ++k)
    for (int s = 0; s < 5; ++s) {
      const std::string y = k == 5 && s == 2 ? "" : std::to_string(0.5 + 0.1 * k + 0.3 * s);
      const std::string ci = (k + s) % 3 == 0 ? "" : std::to_string(0.05 * (1 + s));
      text += std::string(categories[k]) + "," + methods[s] + "," + y + "," + ci + "\n";
    }
  return text;
}

}  // namespace

TEST_CASE("PlotBars: a group per category, a slot and colour per series, whiskers, a legend",
          "[results][bar_plot]") {
  const std::string dir = TempDir("bars-script");
  const std::string csv = dir + "/rmse.csv", script = dir + "/script.gp";
  WriteFile(csv, kGroups);
  BarPlotSpec spec;
  spec.title = "RMSE per modality";
  spec.x_label = "Modalities";
  spec.y_label = "RMSE (m)";
  spec.legend_title = "method";
  spec.gnuplot = FakeGnuplot(dir, script);
  CHECK_THAT(PlotBars(csv, spec), Catch::EndsWith("gnuplot wrote no image"));
  const std::string gp = ReadFile(script);

  // Categories in first-seen order, their names as literal strings, the
  // x tics at 0, 1, 2 level.
  CHECK_THAT(gp, Catch::Contains("uavsim_category0 = 'it'.\"'\".'s `A`'\n"
                                 "uavsim_category1 = 'B'\n"
                                 "uavsim_category2 = 'C'\n"));
  CHECK_THAT(gp, !Catch::Contains("uavsim_category3"));
  CHECK_THAT(gp, Catch::Contains(
                     " norotate (uavsim_category0 0, uavsim_category1 1, uavsim_category2 2)\n"));
  CHECK_THAT(gp, Catch::Contains("set xrange [-0.5:2.5]\n"));
  // Per series every bar as (category index, y); "a" has none in B.
  CHECK_THAT(gp, Catch::Contains("$bars0 << EOD\n0 2\n2 4\nEOD\n"));
  CHECK_THAT(gp, Catch::Contains("$bars1 << EOD\n0 3\n1 5\n2 6\nEOD\n"));
  CHECK_THAT(gp, !Catch::Contains("$bars2"));  // "c" has no bar
  CHECK_THAT(gp, !Catch::Contains("uavsim_series2"));
  // Whiskers only where an interval is given: index, y, bottom, top.
  CHECK_THAT(gp, Catch::Contains("$whiskers0 << EOD\n0 2 1.5 2.5\nEOD\n"));
  CHECK_THAT(gp, Catch::Contains("$whiskers1 << EOD\n1 5 4.75 5.25\n2 6 5 7\nEOD\n"));
  // "a" left of "b" in each group, in its own colour; the whiskers at the
  // same x as their bars, drawn after all bars.
  CHECK_THAT(gp, Catch::Contains("$bars0 using ($1+(-0.2)):2 with boxes lc rgb '#1f77b4'"));
  CHECK_THAT(gp, Catch::Contains("$bars1 using ($1+(0.2)):2 with boxes lc rgb '#ff7f0e'"));
  CHECK_THAT(gp, Catch::Contains("$whiskers0 using ($1+(-0.2)):3:(0):($4-$3) with vectors heads"));
  CHECK_THAT(gp, Catch::Contains("$whiskers1 using ($1+(0.2)):3:(0):($4-$3) with vectors heads"));
  CHECK(gp.find("$bars1 using") < gp.find("$whiskers0 using"));
  // y from 0 to the top of the highest whisker (6 + 1) and a margin.
  const std::string range = Between(gp, "set yrange [", "]");
  REQUIRE(range.substr(0, 2) == "0:");
  CHECK(std::stod(range.substr(2)) == Approx(7.35));
  CHECK_THAT(gp, !Catch::Contains("\nset logscale"));
  // One legend, in a strip below: "a", "b" and the whiskers; none in the plot.
  CHECK_THAT(gp, Catch::Contains("unset key\n"));
  CHECK(Count(gp, "set key ") == 1);
  CHECK_THAT(gp, Catch::Contains("set key center center horizontal"));
  CHECK_THAT(gp, Catch::Contains("title uavsim_key"));
  CHECK_THAT(gp, Catch::Contains("NaN with boxes lc rgb '#1f77b4' fs solid 0.85 border lc rgb "
                                 "'#333333' title uavsim_series0"));
  CHECK_THAT(gp, Catch::Contains("title uavsim_series1"));
  CHECK_THAT(gp, Catch::Contains("uavsim_ci = '95 % CI of the mean'\n"));
  CHECK_THAT(gp, Catch::Contains("title uavsim_ci"));
  CHECK(Count(gp, "\nplot ") == 2);  // the bars and the legend
  CHECK_THAT(gp, Catch::Contains("set label 1 uavsim_xlabel at screen "));
  CHECK_THAT(gp, Catch::Contains(" size 900,560 "));
}

TEST_CASE("PlotBars: a missing bar leaves its slot; one series is centred", "[results][bar_plot]") {
  const std::string dir = TempDir("bars-slots");
  const std::string csv = dir + "/rmse.csv", script = dir + "/script.gp";
  BarPlotSpec spec;
  spec.gnuplot = FakeGnuplot(dir, script);
  // "m" has no bar in "q": the "m" bar of "p" and both others keep their x.
  WriteFile(csv,
            "category,series,y,ci95\n"
            "p,l,1,\np,m,2,\np,r,3,\n"
            "q,l,4,\nq,m,,\nq,r,6,\n");
  PlotBars(csv, spec);
  std::string gp = ReadFile(script);
  CHECK_THAT(gp, Catch::Contains("$bars1 << EOD\n0 2\nEOD\n"));
  CHECK_THAT(gp, Catch::Contains("$bars1 using ($1+(0)):2 with boxes"));
  const std::string left = Between(gp, "$bars0 using ($1+(", ")");
  const std::string right = Between(gp, "$bars2 using ($1+(", ")");
  REQUIRE_FALSE(left.empty());
  REQUIRE_FALSE(right.empty());
  CHECK(std::stod(left) == Approx(-0.8 / 3));
  CHECK(std::stod(right) == Approx(0.8 / 3));
  CHECK_THAT(gp, Catch::Contains("$bars2 << EOD\n0 3\n1 6\nEOD\n"));
  CHECK_THAT(gp, !Catch::Contains("$whiskers"));  // no interval anywhere
  CHECK_THAT(gp, !Catch::Contains("title uavsim_ci"));

  // A category without any bar keeps its place on the x axis.
  WriteFile(csv, "category,series,y,ci95\np,l,1,0.5\nempty,l,,\nq,l,3,\n");
  PlotBars(csv, spec);
  gp = ReadFile(script);
  CHECK_THAT(gp, Catch::Contains("(uavsim_category0 0, uavsim_category1 1, uavsim_category2 2)"));
  CHECK_THAT(gp, Catch::Contains("uavsim_category1 = 'empty'\n"));
  CHECK_THAT(gp, Catch::Contains("$bars0 << EOD\n0 1\n2 3\nEOD\n"));
  CHECK_THAT(gp, Catch::Contains("$bars0 using ($1+(0)):2 with boxes"));
  CHECK(std::stod(Between(gp, "set boxwidth ", " ")) == Approx(0.6 * 0.88));
}

TEST_CASE("PlotBars: long or many category names are turned", "[results][bar_plot]") {
  const std::string dir = TempDir("bars-turned");
  const std::string csv = dir + "/rmse.csv", script = dir + "/script.gp";
  BarPlotSpec spec;
  spec.gnuplot = FakeGnuplot(dir, script);
  WriteFile(csv, "category,series,y,ci95\ncamera,a,1,\nlidar,a,2,\n");
  PlotBars(csv, spec);
  CHECK_THAT(ReadFile(script), Catch::Contains("set xtics scale 0 nomirror norotate ("));
  // Four groups of 199 pixels, the first name about 340 pixels long.
  WriteFile(csv,
            "category,series,y,ci95\ncamera+lidar+radar+gnss+imu+barometer,a,1,\n"
            "lidar,a,2,\nradar,a,3,\ncamera,a,4,\n");
  PlotBars(csv, spec);
  std::string gp = ReadFile(script);
  CHECK_THAT(gp, Catch::Contains("set xtics scale 0 nomirror rotate by 45 right ("));
  // The plot moves right so that the first turned label stays in the image.
  CHECK(std::stod(Between(gp, "set lmargin at screen ", "\n")) > 84.0 / 900);
  std::string many = "category,series,y,ci95\n";
  for (int k = 0; k < 40; ++k) many += "case " + std::to_string(k) + ",a,1,\n";
  WriteFile(csv, many);
  PlotBars(csv, spec);
  gp = ReadFile(script);
  CHECK_THAT(gp, Catch::Contains("rotate by 45 right ("));
  CHECK_THAT(gp, Catch::Contains("uavsim_category39 39)\n"));
}

TEST_CASE("PlotBars: a logarithmic axis, other column names", "[results][bar_plot]") {
  const std::string dir = TempDir("bars-log");
  const std::string csv = dir + "/rmse.csv", script = dir + "/script.gp";
  BarPlotSpec spec;
  spec.gnuplot = FakeGnuplot(dir, script);
  spec.log_y = true;
  spec.y_min_zero = true;  // ignored on a log axis
  spec.category_column = "modalities";
  spec.series_column = "method";
  spec.y_column = "rmse_m";
  spec.ci95_column = "rmse_ci95_m";
  // 1 - 5 < 0: its whisker's bottom is the axis's bottom.
  WriteFile(csv,
            "method,rmse_m,rmse_ci95_m,modalities,other\nGRU,1,5,camera,x\nGRU,100,1,lidar,y\n");
  CHECK_THAT(PlotBars(csv, spec), Catch::EndsWith("gnuplot wrote no image"));
  const std::string gp = ReadFile(script);
  CHECK_THAT(gp, Catch::Contains("set logscale y\n"));
  CHECK_THAT(gp, Catch::Contains("uavsim_category0 = 'camera'\nuavsim_category1 = 'lidar'\n"));
  CHECK_THAT(gp, Catch::Contains("uavsim_series0 = 'GRU'\n"));
  const std::string bottom = Between(gp, "set yrange [", ":");
  REQUIRE_FALSE(bottom.empty());
  CHECK(std::stod(bottom) > 0.0);
  CHECK(std::stod(bottom) < 1.0);
  CHECK_THAT(gp, Catch::Contains("$whiskers0 << EOD\n0 1 " + bottom + " 6\n1 100 99 101\nEOD\n"));
}

TEST_CASE("PlotBars: gnuplot draws the bars", "[results][bar_plot]") {
  const std::string dir = TempDir("bars-draw");
  const std::string csv = dir + "/rmse.csv";
  WriteFile(csv, ModalityTable());
  BarPlotSpec spec;
  spec.title = "it's a \"figure\", `touch pwned`";
  spec.x_label = "Modalities";
  spec.y_label = "RMSE (m)";
  spec.legend_title = "method";
  const std::string drawn = PlotBars(csv, spec);
  if (drawn.find("gnuplot not found") != std::string::npos) {
    WARN("gnuplot is not installed: " << drawn);
    return;
  }
  CHECK(drawn == "");
  const auto [width, height] = PngSize(dir + "/rmse.png");
  CHECK(width == 900);
  CHECK(height == 560);
  CHECK(fs::file_size(dir + "/rmse.png") > 1000);
  CHECK_FALSE(fs::exists(fs::current_path() / "pwned"));
  CHECK_FALSE(fs::exists(dir + "/pwned"));

  spec.png_path = dir + "/small.png";
  spec.width_px = 720;
  spec.height_px = 480;
  CHECK(PlotBars(csv, spec) == "");
  const auto [small_width, small_height] = PngSize(dir + "/small.png");
  CHECK(small_width == 720);
  CHECK(small_height == 480);
  for (const auto& e : fs::directory_iterator(dir))
    CHECK(e.path().filename().string().find(".png.tmp") == std::string::npos);
}

TEST_CASE("PlotBars: problems are one line, and leave no image", "[results][bar_plot]") {
  const std::string dir = TempDir("bars-errors");
  const std::string csv = dir + "/rmse.csv", png = dir + "/rmse.png";
  BarPlotSpec spec;
  const auto plot = [&](const std::string& text) {
    WriteFile(csv, text);
    const std::string message = PlotBars(csv, spec);
    CHECK_THAT(message, Catch::StartsWith("bar plot " + csv + ": "));
    CHECK(message.find('\n') == std::string::npos);
    CHECK_FALSE(fs::exists(png));
    return message;
  };
  const std::string h = "category,series,y,ci95\n";
  CHECK_THAT(PlotBars(dir + "/absent.csv", spec), Catch::EndsWith("cannot read the file"));
  CHECK_THAT(plot(""), Catch::EndsWith("the file is empty"));
  CHECK_THAT(plot("category,series,y\nA,a,1\n"), Catch::EndsWith("no column \"ci95\""));
  CHECK_THAT(plot("series,y,ci95\na,1,\n"), Catch::EndsWith("no column \"category\""));
  CHECK_THAT(plot(h + "A,a,1\n"), Catch::Contains("line 2 has 3 cells, the header 4"));
  CHECK_THAT(plot(h + "A,a,1,\nB,a,nan,\n"),
             Catch::EndsWith("line 3: expected an empty cell or a finite number in \"y\""));
  CHECK_THAT(plot(h + "A,a,inf,\n"),
             Catch::EndsWith("line 2: expected an empty cell or a finite number in \"y\""));
  CHECK_THAT(plot(h + "A,a,1 m,\n"),
             Catch::EndsWith("line 2: expected an empty cell or a finite number in \"y\""));
  CHECK_THAT(plot(h + "A,a,1,-0.5\n"),
             Catch::EndsWith("line 2: expected an empty cell or a finite number >= 0 in \"ci95\""));
  CHECK_THAT(plot(h + "A,a,1,inf\n"),
             Catch::EndsWith("line 2: expected an empty cell or a finite number >= 0 in \"ci95\""));
  CHECK_THAT(plot(h + "A,a,1,\nB,a,2,\nA,a,3,\n"),
             Catch::EndsWith("line 4: a second row for category \"A\" and series \"a\" (the first "
                             "on line 2)"));
  CHECK_THAT(plot(h), Catch::EndsWith("no bar to draw (every \"y\" cell is empty)"));
  CHECK_THAT(plot(h + "A,a,,0.5\nB,b,,\n"), Catch::Contains("no bar to draw"));
  spec.log_y = true;
  CHECK_THAT(plot(h + "A,a,0,\n"), Catch::EndsWith("line 2: y must be > 0 on a logarithmic axis"));
  spec.log_y = false;
  spec.y_column = "rmse_m";
  CHECK_THAT(plot(h + "A,a,1,\n"), Catch::EndsWith("no column \"rmse_m\""));
  CHECK_THAT(plot("category,series,rmse_m,ci95\nA,a,x,\n"),
             Catch::EndsWith("line 2: expected an empty cell or a finite number in \"rmse_m\""));
  spec = BarPlotSpec();
  spec.width_px = 100;
  CHECK_THAT(plot(h + "A,a,1,\n"), Catch::Contains("at least 320 x 240"));
  spec.width_px = 9000;
  CHECK_THAT(plot(h + "A,a,1,\n"), Catch::Contains("at most 8192 x 8192 pixels"));
  spec = BarPlotSpec();
  spec.height_px = 240;
  // Long names of four categories, turned, need more height than there is.
  std::string crowded = h;
  for (int k = 0; k < 4; ++k)
    for (int s = 0; s < 2; ++s)
      crowded += "camera+lidar+radar+gnss+imu+barometer " + std::to_string(k) + ",method " +
                 std::to_string(s) + ",1,\n";
  CHECK_THAT(plot(crowded), Catch::Contains("a 900 x 240 image leaves no room for the bars"));
  spec = BarPlotSpec();
  spec.gnuplot = dir + "/no-such-gnuplot";
  CHECK_THAT(plot(h + "A,a,1,\n"), Catch::Contains("gnuplot not found"));

  // gnuplot failing, with an older image there: the message carries the
  // first line gnuplot printed, the older image stays as it was.
  const std::string failing = dir + "/failing-gnuplot";
  WriteFile(failing, "#!/bin/sh\necho '\"x.gp\" line 9: unknown option'\necho more\nexit 1\n");
  fs::permissions(failing, fs::perms::owner_all);
  spec.gnuplot = failing;
  WriteFile(png, "an older image");
  WriteFile(csv, h + "A,a,1,\n");
  const std::string failed = PlotBars(csv, spec);
  CHECK(failed == "bar plot " + csv + ": gnuplot failed: \"x.gp\" line 9: unknown option");
  spec = BarPlotSpec();
  WriteFile(csv, h + "A,a,nan,\n");
  CHECK_THAT(PlotBars(csv, spec), Catch::Contains("line 2: expected"));
  CHECK(ReadFile(png) == "an older image");
  // No other image, and no temporary one, left behind by any of them.
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    CHECK((e.path().extension() != ".png" || name == "rmse.png"));
    CHECK(name.find(".png.tmp") == std::string::npos);
  }
}
