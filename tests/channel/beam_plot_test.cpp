// rate_snr.csv from the accumulator drawn by the gnuplot driver: a PNG beside
// the CSV, texts that cannot inject commands, and messages instead of crashes.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "channel/beamformer.h"
#include "results/plot.h"

namespace fs = std::filesystem;
using uavsim::results::PlotCsv;
using uavsim::results::PlotSpec;

namespace {

struct ScratchDir {
  fs::path path = fs::temp_directory_path() / ("uavsim-beam-plot-" + std::to_string(getpid()));
  ScratchDir() { fs::create_directories(path); }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::string Slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

PlotSpec RateSpec() {
  PlotSpec s;
  s.title = "Achievable rate vs SNR";
  s.x_label = "SNR (dB)";
  s.y_label = "Rate (bit/s/Hz)";
  s.x_column = "snr_db";
  s.y_column = "rate_bps_hz";
  s.group_column = "beam";
  return s;
}

}  // namespace

TEST_CASE("Plot: rate_snr.csv becomes a PNG beside it", "[channel]") {
  ScratchDir dir;
  uavsim::channel::RateSnrAccumulator acc(uavsim::channel::SnrGridDb(-10.0, 30.0, 2.0));
  acc.Add("perfect", 64.0);
  acc.Add("uavloc", 50.0);
  acc.Add("ekf", 20.0);
  const fs::path csv = dir.path / "rate_snr.csv";
  std::ofstream(csv) << acc.Csv();

  const std::string error = PlotCsv(csv.string(), RateSpec());
  if (error.find("gnuplot not found") != std::string::npos) {
    WARN("gnuplot is not installed: " << error);
    return;
  }
  REQUIRE(error.empty());
  const std::string png = Slurp(dir.path / "rate_snr.png");
  REQUIRE(png.size() > 1000);
  CHECK(png.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0);
  // Only the PNG and the CSV: no temporary left behind.
  CHECK(std::distance(fs::directory_iterator(dir.path), fs::directory_iterator()) == 2);

  // Texts are data, never commands: quotes, backquotes, macros, newlines.
  const fs::path canary = dir.path / "pwned";
  PlotSpec evil = RateSpec();
  evil.title = "it's `touch " + canary.string() + "` @x\nsystem('touch " + canary.string() + "')";
  evil.x_label = "'; system('touch " + canary.string() + "'); print '";
  evil.png_path = (dir.path / "it's a plot.png").string();
  CHECK(PlotCsv(csv.string(), evil) == "");
  CHECK(fs::exists(dir.path / "it's a plot.png"));
  CHECK_FALSE(fs::exists(canary));
}

TEST_CASE("Plot: problems come back as messages", "[channel]") {
  ScratchDir dir;
  const fs::path csv = dir.path / "rate_snr.csv";
  std::ofstream(csv) << "snr_db,beam,rate_bps_hz\n0.00,perfect,1.5\n";

  PlotSpec missing = RateSpec();
  missing.gnuplot = (dir.path / "no-such-gnuplot").string();
  CHECK_THAT(PlotCsv(csv.string(), missing), Catch::Contains("gnuplot not found"));
  CHECK_FALSE(fs::exists(dir.path / "rate_snr.png"));

  PlotSpec wrong = RateSpec();
  wrong.y_column = "rate";
  CHECK_THAT(PlotCsv(csv.string(), wrong), Catch::EndsWith("no column \"rate\""));
  CHECK_THAT(PlotCsv((dir.path / "absent.csv").string(), RateSpec()),
             Catch::EndsWith("cannot read the file"));

  std::ofstream(csv) << "snr_db,beam,rate_bps_hz\n0.00,perfect,nan\n";
  CHECK_THAT(PlotCsv(csv.string(), RateSpec()), Catch::Contains("line 2: expected finite numbers"));
  std::ofstream(csv) << "snr_db,beam,rate_bps_hz\n";
  CHECK_THAT(PlotCsv(csv.string(), RateSpec()), Catch::EndsWith("no data rows"));
}
