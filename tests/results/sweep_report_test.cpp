// The sweep report: summary, aggregate and small-multiple tables checked
// against values worked out by hand (t from the printed table), plots drawn
// by gnuplot, report.html (its links, tables and escaping), and the gnuplot
// driver's error bars, missing values and axis options.
#include "results/sweep_report.h"

#include <stdlib.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "results/csv.h"
#include "results/plot.h"
#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::core::Json;
using uavsim::results::PlotCsv;
using uavsim::results::PlotSpec;
using uavsim::results::StudentT975;
using uavsim::results::SweepAxis;
using uavsim::results::SweepPoint;
using uavsim::results::SweepReportInputs;
using uavsim::results::WriteSweepReport;
using uavsim::testing::ReadFile;
using uavsim::testing::TempDir;
using uavsim::testing::WriteFile;

namespace {

// t_{0.975, dof} from a printed Student-t table (more digits than usual).
constexpr double kT1 = 12.7062047;
constexpr double kT2 = 4.3026527;

Json Rmse(std::optional<double> x) { return x ? Json(*x) : Json(nullptr); }

Json Packets(int sent, int delivered) {
  return {{"frames", sent},
          {"packets_sent", sent},
          {"packets_delivered", delivered},
          {"packets_late", 0},
          {"packets_lost", sent - delivered}};
}

// metrics.json with ekf and uavloc RMSE and camera and lidar packets.
Json Metrics(std::optional<double> ekf, std::optional<double> uavloc, int camera_sent,
             int camera_delivered) {
  Json m = Json::object();
  m["rmse_m"] = {{"ekf", Rmse(ekf)}, {"uavloc", Rmse(uavloc)}};
  m["modalities"] = {{"camera", Packets(camera_sent, camera_delivered)}, {"lidar", Packets(0, 0)}};
  m["wall_s"] = 1.25;  // ignored: no wall times in the report
  return m;
}

// rate_snr.csv as the runs write it, for the SNRs -10 and 2.5 dB.
std::string Rates(double perfect_m10, double perfect_2_5, std::optional<double> ekf_m10,
                  std::optional<double> ekf_2_5) {
  std::string csv = "snr_db,beam,rate_bps_hz\n";
  csv += "-10.00,perfect," + std::to_string(perfect_m10) + "\n";
  csv += "2.50,perfect," + std::to_string(perfect_2_5) + "\n";
  if (ekf_m10) csv += "-10.00,ekf," + std::to_string(*ekf_m10) + "\n";
  if (ekf_2_5) csv += "2.50,ekf," + std::to_string(*ekf_2_5) + "\n";
  return csv;
}

SweepPoint Point(const std::string& id, std::vector<int> value_index, std::uint64_t seed,
                 Json metrics, std::string rates) {
  SweepPoint p;
  p.id = id;
  p.value_index = std::move(value_index);
  p.seed = seed;
  p.metrics = std::move(metrics);
  p.rate_snr_csv = std::move(rates);
  return p;
}

// loss {0.1, 0.2} x weather {clear, fog 100 m}; settings with 3, 1, 2 and 2
// seeds. Setting (0.1, clear): ekf 1, 2, 4; uavloc 3, null, 5; camera 90/100,
// 80/100, 50/50; rate perfect@-10 dB 1, 2, 3 and @2.5 dB 4, 4, 4.
SweepReportInputs Grid() {
  SweepReportInputs in;
  in.title = "loss-weather";
  in.parameters = {{"loss", {"0.1", "0.2"}}, {"weather", {"clear", "fog 100 m"}}};
  in.points.push_back(Point("p0", {0, 0}, 1, Metrics(1, 3, 100, 90), Rates(1, 4, 0.5, 2)));
  in.points.push_back(
      Point("p1", {0, 0}, 2, Metrics(2, std::nullopt, 100, 80), Rates(2, 4, 0.5, 2)));
  in.points.push_back(Point("p2", {0, 0}, 3, Metrics(4, 5, 50, 50), Rates(3, 4, 0.5, 2)));
  // No ekf beam here (it never produced an estimate), and a radar modality.
  Json b = Metrics(6, std::nullopt, 10, 5);
  b["modalities"]["radar"] = Packets(4, 3);
  in.points.push_back(Point("p3", {1, 0}, 1, b, Rates(0.5, 1, std::nullopt, std::nullopt)));
  in.points.push_back(Point("p4", {0, 1}, 1, Metrics(2, 2, 10, 10), Rates(1, 2, 0.25, 1)));
  Json d = Metrics(3, 4, 10, 9);
  d["rmse_m"]["uavloc_camera"] = 7.5;  // a method only this point has
  in.points.push_back(Point("p5", {0, 1}, 2, d, Rates(1, 2, 0.25, 1)));
  in.points.push_back(Point("p6", {1, 1}, 1, Metrics(3, 4, 10, 8), Rates(1, 2, 0.25, 1)));
  in.points.push_back(Point("p7", {1, 1}, 2, Metrics(5, 6, 10, 6), Rates(1, 2, 0.25, 1)));
  SweepAxis loss;
  loss.stem = "loss";
  loss.x_label = "Packet loss probability";
  loss.parameter = 0;
  loss.x_of_value = {{0, 0.1}, {1, 0.2}};
  in.axes.push_back(loss);
  return in;
}

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;

  // The cell of `row` under `column`; fails the test if there is no such
  // column.
  std::string At(std::size_t row, const std::string& column) const {
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == column) return rows.at(row).at(i);
    FAIL("no column " << column);
    return "";
  }
};

Csv ParseCsv(const std::string& text) {
  Csv csv;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = text.find('\n', start);
    REQUIRE(end != std::string::npos);  // every line ends in a newline
    std::vector<std::string> cells = uavsim::results::SplitCsvLine(text.substr(start, end - start));
    if (csv.header.empty())
      csv.header = std::move(cells);
    else {
      REQUIRE(cells.size() == csv.header.size());
      csv.rows.push_back(std::move(cells));
    }
    start = end + 1;
  }
  return csv;
}

double Num(const std::string& cell) {
  REQUIRE_FALSE(cell.empty());
  return std::stod(cell);
}

bool IsPng(const std::string& path) {
  if (!fs::exists(path)) return false;
  const std::string png = ReadFile(path);
  return png.size() > 1000 && png.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0;
}

bool GnuplotMissing(const std::vector<std::string>& failures) {
  for (const auto& f : failures)
    if (f.find("gnuplot not found") != std::string::npos) return true;
  return false;
}

std::size_t Occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Every src="..." and href="..." of a page, in order.
std::vector<std::string> LinksOf(const std::string& html) {
  return uavsim::testing::HtmlReferences(html);
}

// Sets an environment variable for the scope.
struct ScopedEnv {
  std::string name;
  std::optional<std::string> old;
  ScopedEnv(std::string n, const std::string& value) : name(std::move(n)) {
    if (const char* v = std::getenv(name.c_str())) old = v;
    ::setenv(name.c_str(), value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old)
      ::setenv(name.c_str(), old->c_str(), 1);
    else
      ::unsetenv(name.c_str());
  }
};

}  // namespace

TEST_CASE("StudentT975 matches the printed t table", "[results][sweep_report]") {
  CHECK(StudentT975(1) == Approx(12.706).margin(1e-3));
  CHECK(StudentT975(2) == Approx(4.303).margin(1e-3));
  CHECK(StudentT975(4) == Approx(2.776).margin(1e-3));
  CHECK(StudentT975(10) == Approx(2.228).margin(1e-3));
  CHECK(StudentT975(30) == Approx(2.042).margin(1e-3));
  CHECK_THROWS_AS(StudentT975(0), std::invalid_argument);
  CHECK_THROWS_AS(StudentT975(-3), std::invalid_argument);
}

TEST_CASE("Sweep report: summary.csv has a row per point and a column per metric",
          "[results][sweep_report]") {
  const std::string dir = TempDir("sweep-summary");
  WriteSweepReport(dir, Grid());
  const std::string text = ReadFile(dir + "/summary.csv");
  const Csv csv = ParseCsv(text);
  CHECK(csv.header ==
        std::vector<std::string>{"point", "loss", "weather", "seed", "rmse_ekf", "rmse_uavloc",
                                 "rmse_uavloc_camera", "delivery_camera", "delivery_lidar",
                                 "delivery_radar", "rate_perfect_-10dB", "rate_perfect_2.5dB",
                                 "rate_ekf_-10dB", "rate_ekf_2.5dB"});
  REQUIRE(csv.rows.size() == 8);
  // Points in the given order; empty cells for: a null RMSE, a method or
  // modality the point does not have, nothing sent, a beam it has no rows of.
  CHECK(text.find("\np0,0.1,clear,1,1.000000,3.000000,,0.900000,,,1.000000,4.000000,0.500000,"
                  "2.000000\n") != std::string::npos);
  CHECK(text.find("\np1,0.1,clear,2,2.000000,,,0.800000,,,2.000000,") != std::string::npos);
  CHECK(text.find("\np3,0.2,clear,1,6.000000,,,0.500000,,0.750000,0.500000,1.000000,,\n") !=
        std::string::npos);
  CHECK(csv.At(5, "point") == "p5");
  CHECK(csv.At(5, "weather") == "fog 100 m");
  CHECK(csv.At(5, "rmse_uavloc_camera") == "7.500000");
  CHECK(csv.At(7, "delivery_camera") == "0.600000");
}

TEST_CASE("Sweep report: aggregate.csv has mean and 95 % CI per setting",
          "[results][sweep_report]") {
  const std::string dir = TempDir("sweep-aggregate");
  WriteSweepReport(dir, Grid());
  const Csv csv = ParseCsv(ReadFile(dir + "/aggregate.csv"));
  REQUIRE(csv.rows.size() == 4);
  CHECK(csv.header.size() == 3 + 2 * 10);
  CHECK(csv.header[2] == "seeds");
  CHECK(csv.header[3] == "rmse_ekf_mean");
  CHECK(csv.header[4] == "rmse_ekf_ci95");
  CHECK(csv.header.back() == "rate_ekf_2.5dB_ci95");
  // Settings in order of first appearance.
  CHECK(csv.At(0, "loss") == "0.1");
  CHECK(csv.At(0, "weather") == "clear");
  CHECK(csv.At(1, "loss") == "0.2");
  CHECK(csv.At(2, "weather") == "fog 100 m");
  CHECK(csv.At(0, "seeds") == "3");
  CHECK(csv.At(1, "seeds") == "1");

  // ekf 1, 2, 4: mean 7/3, s = sqrt(((4/3)^2 + (1/3)^2 + (5/3)^2) / 2).
  const double s_ekf = std::sqrt((16.0 / 9 + 1.0 / 9 + 25.0 / 9) / 2.0);
  CHECK(csv.At(0, "rmse_ekf_mean") == "2.333333");
  CHECK(Num(csv.At(0, "rmse_ekf_ci95")) == Approx(kT2 * s_ekf / std::sqrt(3.0)).margin(1e-5));
  // uavloc 3, null, 5: n = 2, s = sqrt(2), so the half-width is t_{0.975,1}.
  CHECK(csv.At(0, "rmse_uavloc_mean") == "4.000000");
  CHECK(Num(csv.At(0, "rmse_uavloc_ci95")) == Approx(kT1).margin(1e-5));
  // Camera 0.9, 0.8, 1.0: s = 0.1.
  CHECK(csv.At(0, "delivery_camera_mean") == "0.900000");
  CHECK(Num(csv.At(0, "delivery_camera_ci95")) == Approx(kT2 * 0.1 / std::sqrt(3.0)).margin(1e-5));
  // Rates 1, 2, 3 (s = 1) and 4, 4, 4 (s = 0).
  CHECK(csv.At(0, "rate_perfect_-10dB_mean") == "2.000000");
  CHECK(Num(csv.At(0, "rate_perfect_-10dB_ci95")) == Approx(kT2 / std::sqrt(3.0)).margin(1e-5));
  CHECK(csv.At(0, "rate_perfect_2.5dB_ci95") == "0.000000");
  // No value at all: both empty; one value: a mean, no interval.
  CHECK(csv.At(0, "delivery_lidar_mean").empty());
  CHECK(csv.At(0, "delivery_lidar_ci95").empty());
  CHECK(csv.At(0, "rmse_uavloc_camera_mean").empty());
  CHECK(csv.At(1, "rmse_ekf_mean") == "6.000000");
  CHECK(csv.At(1, "rmse_ekf_ci95").empty());
  CHECK(csv.At(1, "rmse_uavloc_mean").empty());
  CHECK(csv.At(1, "rate_ekf_-10dB_mean").empty());
  CHECK(csv.At(2, "rmse_uavloc_camera_mean") == "7.500000");
  CHECK(csv.At(2, "rmse_uavloc_camera_ci95").empty());
  // ekf 3, 5: mean 4, s = sqrt(2).
  CHECK(csv.At(3, "rmse_ekf_mean") == "4.000000");
  CHECK(Num(csv.At(3, "rmse_ekf_ci95")) == Approx(kT1).margin(1e-5));
}

TEST_CASE("Sweep report: the same inputs give the same bytes", "[results][sweep_report]") {
  const std::string a = TempDir("sweep-same"), b = TempDir("sweep-same");
  WriteSweepReport(a, Grid());
  WriteSweepReport(b, Grid());
  std::vector<std::string> files{"summary.csv", "aggregate.csv"};
  for (const auto& e : fs::directory_iterator(fs::path(a) / "plots"))
    if (e.path().extension() == ".csv") files.push_back("plots/" + e.path().filename().string());
  // rmse_loss, delivery_loss, rate_snr_000..003, panels_rmse_loss,
  // panels_delivery_loss, panels_rate_snr
  CHECK(files.size() == 2 + 2 + 4 + 3);
  files.push_back("report.html");
  for (const auto& f : files) {
    INFO(f);
    CHECK(ReadFile(a + "/" + f) == ReadFile(b + "/" + f));
  }
}

TEST_CASE("Sweep report: curves along an axis, a line per method and other setting",
          "[results][sweep_report]") {
  const std::string dir = TempDir("sweep-plots");
  SweepReportInputs in = Grid();
  SweepAxis weather;  // a single x value: nothing to draw
  weather.stem = "weather";
  weather.x_label = "Fog visibility (m)";
  weather.parameter = 1;
  weather.x_of_value = {{1, 100.0}};
  in.axes.push_back(weather);
  const std::vector<std::string> failures = WriteSweepReport(dir, in);
  const std::string plots = dir + "/plots/";

  const Csv rmse = ParseCsv(ReadFile(plots + "rmse_loss.csv"));
  CHECK(rmse.header == std::vector<std::string>{"x", "y", "ci95", "series"});
  // 3 methods x 2 weathers x 2 losses, less the one series without any
  // value (uavloc_camera ran only in a fog point); the series
  // names the other parameter (its comma made a ';' for the plain CSV).
  REQUIRE(rmse.rows.size() == 10);
  for (std::size_t i = 0; i < rmse.rows.size(); ++i)
    CHECK(rmse.At(i, "series") != "uavloc_camera; weather=clear");
  CHECK(rmse.rows[0] ==
        std::vector<std::string>{"0.1", "2.333333", rmse.At(0, "ci95"), "ekf; weather=clear"});
  CHECK(rmse.rows[1] == std::vector<std::string>{"0.2", "6.000000", "", "ekf; weather=clear"});
  CHECK(rmse.rows[2] ==
        std::vector<std::string>{"0.1", "2.500000", rmse.At(2, "ci95"), "ekf; weather=fog 100 m"});
  CHECK(rmse.rows[5] == std::vector<std::string>{"0.2", "", "", "uavloc; weather=clear"});
  const Csv delivery = ParseCsv(ReadFile(plots + "delivery_loss.csv"));
  // camera (2 weathers x 2 losses), radar in clear weather only (its one
  // point); lidar never had a packet sent: no series.
  REQUIRE(delivery.rows.size() == 6);
  CHECK(delivery.At(0, "series") == "camera; weather=clear");
  CHECK(delivery.At(0, "y") == "0.900000");
  const Csv rate = ParseCsv(ReadFile(plots + "rate_snr_000.csv"));
  CHECK(rate.rows ==
        std::vector<std::vector<std::string>>{{"-10", "2.000000", rate.At(0, "ci95"), "perfect"},
                                              {"2.5", "4.000000", "0.000000", "perfect"},
                                              {"-10", "0.500000", "0.000000", "ekf"},
                                              {"2.5", "2.000000", "0.000000", "ekf"}});
  CHECK_FALSE(fs::exists(plots + "rmse_weather.csv"));
  CHECK_FALSE(fs::exists(plots + "rmse_weather.png"));
  CHECK_FALSE(fs::exists(plots + "delivery_weather.png"));

  if (GnuplotMissing(failures)) {
    WARN("gnuplot is not installed: " << failures.front());
    return;
  }
  CHECK(failures.empty());
  CHECK(IsPng(plots + "rmse_loss.png"));
  CHECK(IsPng(plots + "delivery_loss.png"));
  for (const char* k : {"000", "001", "002", "003"}) CHECK(IsPng(plots + "rate_snr_" + k + ".png"));
  CHECK_FALSE(fs::exists(plots + "rate_snr_004.csv"));
}

TEST_CASE("Sweep report: labels with quotes and commas stay plain cells",
          "[results][sweep_report]") {
  const std::string dir = TempDir("sweep-quotes");
  SweepReportInputs in;
  in.title = "it's a \"sweep\", `touch pwned`";
  in.parameters = {{"loss", {"0.1", "0.2"}}, {"weather", {"it's \"fog\", 100 m"}}};
  in.points.push_back(Point("p0", {0, 0}, 7, Metrics(1, 2, 10, 10), Rates(1, 2, 0.5, 1)));
  in.points.push_back(Point("p1", {1, 0}, 7, Metrics(2, 3, 10, 5), Rates(1, 2, 0.5, 1)));
  SweepAxis loss;
  loss.stem = "loss";
  loss.x_label = "Packet loss probability, log scale";
  loss.parameter = 0;
  loss.x_of_value = {{0, 0.1}, {1, 0.2}};
  loss.log_x = true;
  in.axes.push_back(loss);
  const std::vector<std::string> failures = WriteSweepReport(dir, in);

  CHECK(ReadFile(dir + "/summary.csv").find("\np0,0.1,it's 'fog'; 100 m,7,1.000000,") !=
        std::string::npos);
  CHECK(ParseCsv(ReadFile(dir + "/aggregate.csv")).At(0, "weather") == "it's 'fog'; 100 m");
  // weather has one value: the series is the method alone.
  const Csv rmse = ParseCsv(ReadFile(dir + "/plots/rmse_loss.csv"));
  CHECK(rmse.At(0, "series") == "ekf");
  CHECK(rmse.At(2, "series") == "uavloc");
  CHECK_FALSE(fs::exists(fs::current_path() / "pwned"));
  if (GnuplotMissing(failures)) {
    WARN("gnuplot is not installed: " << failures.front());
    return;
  }
  CHECK(failures.empty());
  CHECK(IsPng(dir + "/plots/rmse_loss.png"));
  CHECK(IsPng(dir + "/plots/rate_snr_000.png"));
}

TEST_CASE("Sweep report: plots that cannot be drawn are reported, their CSVs kept",
          "[results][sweep_report]") {
  const std::string dir = TempDir("sweep-nognuplot");
  const std::string empty_path = TempDir("sweep-empty-path");
  std::vector<std::string> failures;
  {
    ScopedEnv path("PATH", empty_path);
    failures = WriteSweepReport(dir, Grid());
  }
  REQUIRE(failures.size() == 2 + 4 + 3);
  for (const auto& f : failures) CHECK_THAT(f, Catch::Contains("gnuplot not found"));
  CHECK_THAT(failures.back(), Catch::StartsWith("panel plot "));
  CHECK(fs::exists(dir + "/summary.csv"));
  CHECK(fs::exists(dir + "/plots/rmse_loss.csv"));
  CHECK(fs::exists(dir + "/plots/rate_snr_003.csv"));
  CHECK(fs::exists(dir + "/plots/panels_rmse_loss.csv"));
  CHECK(fs::exists(dir + "/plots/panels_rate_snr.csv"));
  CHECK_FALSE(fs::exists(dir + "/plots/rmse_loss.png"));
  CHECK_FALSE(fs::exists(dir + "/plots/panels_rmse_loss.png"));
  // The report says why, in place of each figure, and shows no image.
  const std::string html = ReadFile(dir + "/report.html");
  CHECK(Occurrences(html, "<p class=\"missing\">Not drawn: panel plot ") == 3);
  CHECK_THAT(html, Catch::Contains("gnuplot not found"));
  CHECK_THAT(html, !Catch::Contains("<img"));
  for (const auto& link : LinksOf(html)) {
    INFO(link);
    CHECK(fs::is_regular_file(dir + "/" + link));
  }
}

TEST_CASE("Sweep report: inconsistent inputs are refused before anything is written",
          "[results][sweep_report]") {
  const std::string dir = TempDir("sweep-invalid");
  SweepReportInputs in = Grid();
  in.points[3].value_index = {1};
  CHECK_THROWS_AS(WriteSweepReport(dir, in), std::invalid_argument);
  in = Grid();
  in.points[3].value_index = {2, 0};
  CHECK_THROWS_WITH(WriteSweepReport(dir, in),
                    Catch::Contains("point p3: no value 2 of parameter loss"));
  in = Grid();
  in.axes[0].stem = "../loss";
  CHECK_THROWS_AS(WriteSweepReport(dir, in), std::invalid_argument);
  in = Grid();
  in.axes[0].x_of_value = {{0, 0.0}, {1, 0.2}};
  in.axes[0].log_x = true;
  CHECK_THROWS_AS(WriteSweepReport(dir, in), std::invalid_argument);
  in = Grid();
  in.points[2].rate_snr_csv = "snr_db,beam,rate_bps_hz\n-10.00,perfect,fast\n";
  CHECK_THROWS_WITH(WriteSweepReport(dir, in), Catch::Contains("point p2: rate_snr.csv line 2"));
  in = Grid();
  in.parameters[1].name = "seed";
  CHECK_THROWS_WITH(WriteSweepReport(dir, in), Catch::Contains("two columns named \"seed\""));
  CHECK(fs::is_empty(dir));
}

TEST_CASE("PlotCsv: error bars, missing values, log x, y from zero, legend below",
          "[results][sweep_report][plot]") {
  const std::string dir = TempDir("plot-errorbars");
  const std::string csv = dir + "/curves.csv";
  WriteFile(csv,
            "x,y,ci95,series\n"
            "1,2,0.5,a b\n"
            "2,,,a b\n"
            "3,4,,a b\n"
            "1,1,0.25,c\n"
            "5,,,d\n");
  PlotSpec spec;
  spec.title = "curves";
  spec.x_label = "x (m)";
  spec.y_label = "y (m)";
  spec.x_column = "x";
  spec.y_column = "y";
  spec.group_column = "series";
  spec.y_error_column = "ci95";
  spec.skip_empty_y = true;
  spec.log_x = true;
  spec.y_min_zero = true;
  spec.key_below = true;

  // A stand-in gnuplot that keeps the script it is given (and draws nothing).
  const std::string fake = dir + "/fake-gnuplot";
  const std::string script = dir + "/script.gp";
  WriteFile(fake, "#!/bin/sh\ncp \"$1\" '" + script + "'\n");
  fs::permissions(fake, fs::perms::owner_all);
  PlotSpec faked = spec;
  faked.gnuplot = fake;
  CHECK_THAT(PlotCsv(csv, faked), Catch::EndsWith("gnuplot wrote no image"));
  const std::string gp = ReadFile(script);
  // Missing y left out, an empty half-width is 0, a group with no value
  // draws no line.
  CHECK_THAT(gp, Catch::Contains("$g0 << EOD\n1 2 0.5\n3 4 0\nEOD\n"));
  CHECK_THAT(gp, Catch::Contains("$g1 << EOD\n1 1 0.25\nEOD\n"));
  CHECK_THAT(gp, !Catch::Contains("$g2"));
  CHECK_THAT(gp, Catch::Contains("uavsim_line0 = 'a b'"));
  CHECK_THAT(gp, Catch::Contains("$g0 using 1:2:3 with yerrorlines title uavsim_line0"));
  CHECK_THAT(gp, Catch::Contains("set logscale x\n"));
  CHECK_THAT(gp, Catch::Contains("set yrange [0:*]\n"));
  CHECK_THAT(gp, Catch::Contains("set key below\n"));
  PlotSpec plain = faked;
  plain.y_error_column.clear();
  plain.log_x = plain.y_min_zero = plain.key_below = false;
  WriteFile(csv, "x,y,ci95,series\n1,2,0.5,a\n");
  PlotCsv(csv, plain);
  const std::string plain_gp = ReadFile(script);
  CHECK_THAT(plain_gp, Catch::Contains("$g0 using 1:2 with linespoints title uavsim_line0"));
  CHECK_THAT(plain_gp, !Catch::Contains("logscale"));
  CHECK_THAT(plain_gp, !Catch::Contains("yrange"));
  CHECK_THAT(plain_gp, Catch::Contains("set key top left\n"));

  // The real gnuplot draws it.
  WriteFile(csv, "x,y,ci95,series\n1,2,0.5,a b\n2,,,a b\n3,4,,a b\n1,1,0.25,c\n");
  const std::string drawn = PlotCsv(csv, spec);
  if (drawn.find("gnuplot not found") != std::string::npos) {
    WARN("gnuplot is not installed: " << drawn);
  } else {
    CHECK(drawn == "");
    CHECK(IsPng(dir + "/curves.png"));
  }

  // Problems: an empty y without skip_empty_y, garbage anywhere, a negative
  // half-width, x <= 0 on a log axis, nothing left to draw.
  PlotSpec strict = spec;
  strict.skip_empty_y = false;
  WriteFile(csv, "x,y,ci95,series\n1,2,0.5,a\n2,,,a\n");
  CHECK_THAT(PlotCsv(csv, strict), Catch::Contains("line 3: expected finite numbers"));
  WriteFile(csv, "x,y,ci95,series\n1,abc,0.5,a\n");
  CHECK_THAT(PlotCsv(csv, spec), Catch::Contains("line 2: expected finite numbers"));
  WriteFile(csv, "x,y,ci95,series\n,,,a\n");
  CHECK_THAT(PlotCsv(csv, spec), Catch::Contains("line 2: expected finite numbers"));
  WriteFile(csv, "x,y,ci95,series\n1,2,-0.5,a\n");
  CHECK_THAT(PlotCsv(csv, spec), Catch::Contains("line 2: expected an empty cell or a finite"));
  WriteFile(csv, "x,y,ci95,series\n1,2,wide,a\n");
  CHECK_THAT(PlotCsv(csv, spec), Catch::Contains("line 2: expected an empty cell or a finite"));
  WriteFile(csv, "x,y,ci95,series\n0,2,0.5,a\n");
  CHECK_THAT(PlotCsv(csv, spec), Catch::Contains("line 2: x must be > 0 on a logarithmic axis"));
  WriteFile(csv, "x,y,ci95,series\n1,,0.5,a\n2,,,b\n");
  CHECK_THAT(PlotCsv(csv, spec), Catch::EndsWith("no data rows"));
  PlotSpec no_column = spec;
  no_column.y_error_column = "half_width";
  CHECK_THAT(PlotCsv(csv, no_column), Catch::EndsWith("no column \"half_width\""));
  // No temporary image left behind by any of them.
  for (const auto& e : fs::directory_iterator(dir))
    CHECK(e.path().filename().string().rfind(".curves.png", 0) == std::string::npos);
}

TEST_CASE("Sweep report: small multiples along an axis, a panel per other setting",
          "[results][sweep_report]") {
  const std::string dir = TempDir("sweep-panels");
  const std::vector<std::string> failures = WriteSweepReport(dir, Grid());
  const std::string plots = dir + "/plots/";
  using Row = std::vector<std::string>;

  // RMSE along loss: a panel per weather; in each a series per method with a
  // value there (uavloc_camera only in fog), a row per loss.
  const Csv rmse = ParseCsv(ReadFile(plots + "panels_rmse_loss.csv"));
  CHECK(rmse.header == Row{"x", "y", "ci95", "series", "panel"});
  REQUIRE(rmse.rows.size() == 10);
  // Clear, loss 0.1: ekf 1, 2, 4 (mean 7/3, s^2 = 7/3); loss 0.2: 6 alone.
  CHECK(rmse.rows[0] == Row{"0.1", "2.333333", rmse.At(0, "ci95"), "ekf", "weather=clear"});
  CHECK(Num(rmse.At(0, "ci95")) ==
        Approx(kT2 * std::sqrt(7.0 / 3.0) / std::sqrt(3.0)).margin(1e-5));
  CHECK(rmse.rows[1] == Row{"0.2", "6.000000", "", "ekf", "weather=clear"});
  // uavloc 3, null, 5 at 0.1; null at 0.2: a missing point.
  CHECK(rmse.rows[2] == Row{"0.1", "4.000000", rmse.At(2, "ci95"), "uavloc", "weather=clear"});
  CHECK(Num(rmse.At(2, "ci95")) == Approx(kT1).margin(1e-5));
  CHECK(rmse.rows[3] == Row{"0.2", "", "", "uavloc", "weather=clear"});
  // Fog: ekf 2, 3 (s = sqrt(1/2): t s / sqrt(2) = t / 2) and 3, 5 (t).
  CHECK(rmse.rows[4] == Row{"0.1", "2.500000", rmse.At(4, "ci95"), "ekf", "weather=fog 100 m"});
  CHECK(Num(rmse.At(4, "ci95")) == Approx(kT1 / 2).margin(1e-5));
  CHECK(rmse.rows[5] == Row{"0.2", "4.000000", rmse.At(5, "ci95"), "ekf", "weather=fog 100 m"});
  CHECK(Num(rmse.At(5, "ci95")) == Approx(kT1).margin(1e-5));
  CHECK(rmse.rows[6] == Row{"0.1", "3.000000", rmse.At(6, "ci95"), "uavloc", "weather=fog 100 m"});
  CHECK(rmse.rows[7] == Row{"0.2", "5.000000", rmse.At(7, "ci95"), "uavloc", "weather=fog 100 m"});
  CHECK(rmse.rows[8] == Row{"0.1", "7.500000", "", "uavloc_camera", "weather=fog 100 m"});
  CHECK(rmse.rows[9] == Row{"0.2", "", "", "uavloc_camera", "weather=fog 100 m"});

  // Delivery: camera everywhere; radar only in clear weather at loss 0.2
  // (3 of 4); lidar never sent a packet.
  const Csv delivery = ParseCsv(ReadFile(plots + "panels_delivery_loss.csv"));
  REQUIRE(delivery.rows.size() == 6);
  CHECK(delivery.rows[0] ==
        Row{"0.1", "0.900000", delivery.At(0, "ci95"), "camera", "weather=clear"});
  CHECK(Num(delivery.At(0, "ci95")) == Approx(kT2 * 0.1 / std::sqrt(3.0)).margin(1e-5));
  CHECK(delivery.rows[1] == Row{"0.2", "0.500000", "", "camera", "weather=clear"});
  CHECK(delivery.rows[2] == Row{"0.1", "", "", "radar", "weather=clear"});
  CHECK(delivery.rows[3] == Row{"0.2", "0.750000", "", "radar", "weather=clear"});
  // Fog camera 10/10, 9/10 (s = sqrt(0.005)) and 8/10, 6/10 (s = sqrt(0.02)).
  CHECK(delivery.rows[4] ==
        Row{"0.1", "0.950000", delivery.At(4, "ci95"), "camera", "weather=fog 100 m"});
  CHECK(Num(delivery.At(4, "ci95")) == Approx(kT1 * 0.05).margin(1e-5));
  CHECK(delivery.rows[5] ==
        Row{"0.2", "0.700000", delivery.At(5, "ci95"), "camera", "weather=fog 100 m"});
  CHECK(Num(delivery.At(5, "ci95")) == Approx(kT1 * 0.1).margin(1e-5));
  // No estimated_windows in these metrics: no coverage.
  CHECK_FALSE(fs::exists(plots + "panels_coverage_loss.csv"));

  // Rate vs SNR: a panel per setting (both parameters vary), a series per
  // beam, a row per SNR; a beam without values keeps its empty rows.
  const Csv rate = ParseCsv(ReadFile(plots + "panels_rate_snr.csv"));
  REQUIRE(rate.rows.size() == 4 * 4);
  CHECK(rate.rows[0] ==
        Row{"-10", "2.000000", rate.At(0, "ci95"), "perfect", "loss=0.1; weather=clear"});
  CHECK(Num(rate.At(0, "ci95")) == Approx(kT2 / std::sqrt(3.0)).margin(1e-5));
  CHECK(rate.rows[3] == Row{"2.5", "2.000000", "0.000000", "ekf", "loss=0.1; weather=clear"});
  CHECK(rate.rows[4] == Row{"-10", "0.500000", "", "perfect", "loss=0.2; weather=clear"});
  CHECK(rate.rows[6] == Row{"-10", "", "", "ekf", "loss=0.2; weather=clear"});
  CHECK(rate.At(8, "panel") == "loss=0.1; weather=fog 100 m");
  CHECK(rate.At(12, "panel") == "loss=0.2; weather=fog 100 m");
  CHECK(rate.rows[15] == Row{"2.5", "1.000000", "0.000000", "ekf", "loss=0.2; weather=fog 100 m"});

  if (GnuplotMissing(failures)) {
    WARN("gnuplot is not installed: " << failures.front());
    return;
  }
  CHECK(failures.empty());
  for (const char* png :
       {"panels_rmse_loss.png", "panels_delivery_loss.png", "panels_rate_snr.png"})
    CHECK(IsPng(plots + png));
}

TEST_CASE("Sweep report: report.html shows the sweep, its figures and tables",
          "[results][sweep_report]") {
  const std::string dir = TempDir("sweep-html");
  const std::vector<std::string> failures = WriteSweepReport(dir, Grid());
  const std::string html = ReadFile(dir + "/report.html");

  CHECK_THAT(html, Catch::StartsWith("<!DOCTYPE html>"));
  CHECK_THAT(html, Catch::Contains("<h1>Sweep loss-weather</h1>"));
  // What varied: 8 points in 4 settings of 1 to 3 seeds; each parameter
  // with its values.
  CHECK_THAT(html, Catch::Contains("8 points: 4 settings (loss and weather) \u00d7 1 to 3 seeds"));
  CHECK_THAT(html, Catch::Contains("<td>weather</td><td>clear; fog 100 m</td>"));
  CHECK_THAT(html, Catch::Contains("Methods: ekf, uavloc, uavloc_camera."));
  // The small multiples, with captions that say what is drawn.
  CHECK_THAT(html, Catch::Contains("<img src=\"plots/panels_rmse_loss.png\""));
  CHECK_THAT(html, Catch::Contains("<img src=\"plots/panels_delivery_loss.png\""));
  CHECK_THAT(html, Catch::Contains("<img src=\"plots/panels_rate_snr.png\""));
  CHECK_THAT(html, Catch::Contains("one panel per weather"));
  CHECK_THAT(html, Catch::Contains("the mean over the 1 to 3 seeds of each setting"));
  CHECK_THAT(html, Catch::Contains("95 % confidence interval"));
  // RMSE and delivery per setting as mean ± ci95 from the aggregate: ekf
  // 2.333 ± 3.795 at (0.1, clear), 6 from one seed at (0.2, clear), uavloc
  // without a value there; camera 0.9 ± 0.248.
  CHECK_THAT(html, Catch::Contains("<td class=\"num\">2.33 \u00b1 3.79</td>"));
  CHECK_THAT(html, Catch::Contains("<td class=\"num\">6.00</td><td>\u2013</td>"));
  CHECK_THAT(html, Catch::Contains("<td class=\"num\">0.900 \u00b1 0.248</td>"));
  CHECK_THAT(html, Catch::Contains("<th>camera</th><th>lidar</th><th>radar</th>"));
  // Links to the tables; every image and link names a file of the sweep.
  CHECK_THAT(html, Catch::Contains("<a href=\"summary.csv\">"));
  CHECK_THAT(html, Catch::Contains("<a href=\"aggregate.csv\">"));
  const std::vector<std::string> links = LinksOf(html);
  CHECK(links.size() == 2 + 3 + 3);  // tables, PNGs, their CSVs
  for (const auto& link : links) {
    INFO(link);
    CHECK(fs::is_regular_file(dir + "/" + link));
    if (link.size() > 4 && link.compare(link.size() - 4, 4, ".png") == 0)
      CHECK(fs::file_size(dir + "/" + link) > 0);
  }
  if (GnuplotMissing(failures)) WARN("gnuplot is not installed: " << failures.front());
}

TEST_CASE("Sweep report: report.html escapes what the sweep names", "[results][sweep_report]") {
  const std::string dir = TempDir("sweep-html-escape");
  SweepReportInputs in = Grid();
  in.title = "<script>x</script>";
  in.parameters[1].labels[0] = "<b>&\"";
  in.parameters[1].name = "w<i>";
  WriteSweepReport(dir, in);
  const std::string html = ReadFile(dir + "/report.html");
  CHECK_THAT(html, Catch::Contains("&lt;b&gt;&amp;&quot;"));
  CHECK_THAT(html, !Catch::Contains("<b>&\""));
  CHECK_THAT(html, Catch::Contains("<th>w&lt;i&gt;</th>"));
  CHECK_THAT(html, !Catch::Contains("<i>"));
  CHECK_THAT(html, Catch::Contains("<h1>Sweep &lt;script&gt;x&lt;/script&gt;</h1>"));
  CHECK_THAT(html, !Catch::Contains("<script>"));
  // The panel CSV holds the label as a plain cell.
  const Csv rmse = ParseCsv(ReadFile(dir + "/plots/panels_rmse_loss.csv"));
  CHECK(rmse.At(0, "panel") == "w<i>=<b>&'");
}
