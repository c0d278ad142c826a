// The run report (results/run_report.h) on a run directory written by hand:
// derived tables worked out by hand, the page's references, and what it does
// without gnuplot or with files of an older run missing.
#include "results/run_report.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>

#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::results::RunReportOptions;
using uavsim::results::WriteRunReport;
using uavsim::testing::ReadFile;
using uavsim::testing::TempDir;
using uavsim::testing::WriteFile;

namespace {

// A 0.6 s run with windows of 0.2 s: truth moving +10 m/s along x; two
// methods; packets chosen so that each window state appears.
std::string HandMadeRun(const std::string& tag, const std::string& name = "hand") {
  const std::string dir = TempDir(tag) + "/run";
  fs::create_directories(dir);
  WriteFile(dir + "/manifest.json", R"({"seed": 3, "scenario_file": "s.json",
    "uavsim_version": "0.1.0", "git_hash": "abc", "started_utc": "2026-12-02T00:00:00Z",
    "scenario": {"name": ")" + name + R"(", "duration_s": 0.6,
      "pipeline": {"window_s": 0.2, "methods": ["good", "bad"], "model": "default"},
      "nodes": [{"id": "cam1", "sensor": {"type": "fisheye_stereo", "rate_hz": 30,
                 "pose": {"position_m": [1, 2, 3]}}, "uplink": "default"}],
      "links": {"default": {"bandwidth_mbps": 20, "latency_ms": 5, "jitter": {"type": "none"},
                            "loss": {"type": "bernoulli", "p": 0.1}}}}})");
  WriteFile(dir + "/metrics.json", R"({"rmse_m": {"good": 0.5, "bad": 5.0, "never": null},
    "windows": 3, "estimated_windows": {"good": 2, "bad": 2, "never": 0},
    "rmse_common_m": {}, "sim_s": 0.6, "wall_s": 2.0, "realtime_factor": 0.3,
    "modalities": {"camera": {"frames": 4, "packets_sent": 4, "packets_delivered": 3,
                   "packets_late": 1, "packets_lost": 0, "packets_in_flight": 0,
                   "latency_s": {"count": 4, "mean": 0.01, "p50": 0.01, "p95": 0.02, "p99": 0.02,
                                 "max": 0.02}}},
    "data_rate_kBps": {"camera": {"raw": 18432.0, "preprocessed": 700.0, "compressed": 2.0}},
    "profile_s": {"setup": 0.5, "node/cam1/capture": 1.0, "other": 0.5}})");
  WriteFile(dir + "/truth.csv",
            "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps\n"
            "0.000000,0.0,0.0,0.0,10,0,0\n0.500000,5.0,0.0,0.0,10,0,0\n"
            "1.000000,10.0,0.0,0.0,10,0,0\n");
  // good at 0.25 s: truth (2.5, 0, 0), estimate off by (0, 3, 4): 5 m.
  // bad at 0.4 s: truth (4, 0, 0), estimate off by (-12, 0, 0)... 12 m.
  WriteFile(dir + "/estimates.csv",
            "t_s,method,x_m,y_m,z_m\n"
            "0.250000,good,2.5,3.0,4.0\n0.400000,bad,-8.0,0.0,0.0\n"
            "0.600000,good,6.0,0.0,0.0\n0.600000,bad,6.0,0.0,1.0\n");
  // Window 0: camera 2 on time (all on time); lidar 1 on time + 1 late
  // (partly); radar 1 late (late). Window 1: camera 1 lost + 1 in flight
  // (lost); radar 1 on time; lidar nothing (none_sent). Window 2: nothing.
  WriteFile(dir + "/packets.csv",
            "t_capture_s,node,modality,sequence,bytes,window,status,t_arrival_s,latency_s\n"
            "0.00,cam1,camera,0,16,0,delivered,0.01,0.010\n"
            "0.05,lid1,lidar,0,16,0,delivered,0.07,0.020\n"
            "0.10,cam1,camera,1,16,0,delivered,0.14,0.040\n"
            "0.12,rad1,radar,0,16,0,late,0.45,0.330\n"
            "0.15,lid1,lidar,1,16,0,late,0.30,0.150\n"
            "0.25,cam1,camera,2,16,1,lost,,\n"
            "0.30,rad1,radar,1,16,1,delivered,0.31,0.010\n"
            "0.35,cam1,camera,3,16,1,in_flight,,\n");
  WriteFile(dir + "/world_top.csv",
            "x_m,y_m,height_m,surface\n10.0,10.0,20.00,concrete\n10.5,10.0,20.00,concrete\n"
            "0.0,5.0,6.00,foliage\n");
  WriteFile(dir + "/layout.csv",
            "object,kind,x_m,y_m,z_m\ncam1,camera,1,2,3\nbase_station,base_station,0,0,10\n"
            "cam1,fov,1,2,3\ncam1,fov,11,2,3\ncam1,fov,1,12,3\ncam1,fov,1,2,3\n");
  WriteFile(dir + "/rate_snr.csv",
            "snr_db,beam,rate_bps_hz\n0,perfect,1.0\n0,good,0.9\n10,perfect,3.4\n10,good,3.0\n");
  WriteFile(dir + "/rate_snr_common.csv",
            "snr_db,beam,rate_bps_hz\n0,perfect,1.0\n0,good,0.95\n10,perfect,3.4\n10,good,3.2\n");
  return dir;
}

// Every src="..." and href="..." of the page.
std::set<std::string> References(const std::string& html) {
  const auto refs = uavsim::testing::HtmlReferences(html);
  return {refs.begin(), refs.end()};
}

}  // namespace

TEST_CASE("Run report: derived tables worked by hand", "[results][run_report]") {
  const std::string dir = HandMadeRun("report-tables");
  WriteRunReport(dir);
  // Truth interpolated linearly: at 0.25 s (2.5, 0, 0), at 0.4 s (4, 0, 0).
  CHECK(ReadFile(dir + "/report/errors.csv") ==
        "t_s,method,error_m,east_m,north_m,up_m\n"
        "0.250000,good,5.000000,0.000000,3.000000,4.000000\n"
        "0.600000,good,0.000000,0.000000,0.000000,0.000000\n"
        "0.400000,bad,12.000000,-12.000000,0.000000,0.000000\n"
        "0.600000,bad,1.000000,0.000000,0.000000,1.000000\n");
  const std::string windows = ReadFile(dir + "/report/windows.csv");
  CHECK_THAT(windows, Catch::StartsWith("window,t_start_s,t_end_s,modality,sent,delivered,late,"
                                        "lost,in_flight,state\n"));
  for (const char* row :
       {"0,0.000000,0.200000,camera,2,2,0,0,0,on_time\n",
        "0,0.000000,0.200000,lidar,2,1,1,0,0,partly\n",
        "0,0.000000,0.200000,radar,1,0,1,0,0,late\n", "1,0.200000,0.400000,camera,2,0,0,1,1,lost\n",
        "1,0.200000,0.400000,lidar,0,0,0,0,0,none_sent\n",
        "1,0.200000,0.400000,radar,1,1,0,0,0,on_time\n",
        "2,0.400000,0.600000,camera,0,0,0,0,0,none_sent\n"}) {
    INFO(row);
    CHECK(windows.find(row) != std::string::npos);
  }
  // Three windows of 0.6 s, three modalities: 9 rows.
  CHECK(std::count(windows.begin(), windows.end(), '\n') == 1 + 9);
  CHECK(ReadFile(dir + "/report/packets_by_fate.csv") ==
        "modality,delivered,late,lost,in_flight\ncamera,2,0,1,1\nlidar,1,1,0,0\nradar,1,1,0,0\n");
  // Latency CDF: camera's two arrivals 10 and 40 ms at 1/2 and 1.
  const std::string latency = ReadFile(dir + "/report/latency.csv");
  CHECK(latency.find("camera,10.000,0.500000\ncamera,40.000,1.000000\n") != std::string::npos);
  CHECK(latency.find("radar,10.000,0.500000\nradar,330.000,1.000000\n") != std::string::npos);
}

TEST_CASE("Run report: the page shows the figures and tables, every reference exists",
          "[results][run_report]") {
  const std::string dir = HandMadeRun("report-page", R"(a <b>&\"name\")");  // JSON text
  const auto warnings = WriteRunReport(dir);
  const std::string html = ReadFile(dir + "/report.html");
  if (uavsim::testing::FindOnPath("gnuplot").empty()) {
    WARN("gnuplot not installed: only the page is checked");
  } else {
    CHECK(warnings.empty());
    for (const char* png : {"report/top_view.png", "report/error_time.png", "report/packets.png",
                            "report/latency.png", "rate_snr.png", "rate_snr_common.png"}) {
      INFO(png);
      CHECK(html.find(std::string("src=\"") + png + "\"") != std::string::npos);
      REQUIRE(fs::exists(dir + "/" + png));
      CHECK(fs::file_size(dir + "/" + png) > 1000);
    }
  }
  for (const std::string& ref : References(html)) {
    INFO(ref);
    CHECK(fs::is_regular_file(dir + "/" + ref));
  }
  // The name is escaped, never markup.
  CHECK(html.find("a &lt;b&gt;&amp;&quot;name&quot;") != std::string::npos);
  CHECK(html.find("<b>&") == std::string::npos);
  // RMSE table: both methods and the one that never estimated; medians of
  // good's errors (5 and 0 m: 2.5) and bad's (12 and 1: 6.5).
  CHECK(html.find("<td>good</td><td class=\"num\">0.500</td><td class=\"num\">2</td>") !=
        std::string::npos);
  CHECK(html.find("<td class=\"num\">2.500</td>") != std::string::npos);
  CHECK(html.find("<td class=\"num\">6.500</td>") != std::string::npos);
  CHECK(html.find("<td>never</td><td>-</td>") != std::string::npos);
  // Data rates as the paper's Table II, with the compression ratio.
  CHECK(html.find("<td class=\"num\">9216x</td>") != std::string::npos);
  // Where the time went: largest first, share of wall_s.
  CHECK(html.find("node/cam1/capture</td><td class=\"num\">1.00</td><td class=\"num\">50.0 %") !=
        std::string::npos);
  CHECK(html.find("node/cam1/capture") < html.find("<td>setup</td>"));
  // Settings from the manifest.
  CHECK(html.find("20 Mbit/s, latency 5 ms, jitter none, loss bernoulli p = 0.1") !=
        std::string::npos);
}

TEST_CASE("Run report: without gnuplot or an older run's files, the page says what is missing",
          "[results][run_report]") {
  const std::string dir = HandMadeRun("report-missing");
  fs::remove(dir + "/packets.csv");
  fs::remove(dir + "/rate_snr_common.csv");  // runs before issue 19's common windows
  RunReportOptions o;
  o.gnuplot = "/nonexistent/gnuplot";
  const auto warnings = WriteRunReport(dir, o);
  const std::string html = ReadFile(dir + "/report.html");
  CHECK(html.find("Not drawn: the run has no packets.csv") != std::string::npos);
  CHECK(html.find("Not drawn: gnuplot not found") != std::string::npos);
  CHECK(html.find("Not drawn: the run has no rate_snr_common.csv") != std::string::npos);
  CHECK(References(html).count("report/top_view.png") == 0);
  CHECK(!fs::exists(dir + "/report/top_view.png"));
  CHECK(!fs::exists(dir + "/report/windows.csv"));
  // One warning per figure: top view, error vs time, packets, rate vs SNR
  // on all windows and on common ones.
  CHECK(warnings.size() == 5);
  for (const auto& w : warnings) CHECK(!w.empty());
}

TEST_CASE("Run report: no common window is said on the page, not warned about",
          "[results][run_report]") {
  const std::string dir = HandMadeRun("report-no-common");
  WriteFile(dir + "/rate_snr_common.csv", "snr_db,beam,rate_bps_hz\n");
  const auto warnings = WriteRunReport(dir);
  const std::string html = ReadFile(dir + "/report.html");
  CHECK(html.find("no window in which every method that steers a beam had an estimate") !=
        std::string::npos);
  CHECK(!fs::exists(dir + "/rate_snr_common.png"));
  for (const auto& w : warnings) CHECK_THAT(w, !Catch::Contains("rate_snr_common"));
}

TEST_CASE("Run report: refuses what is not a run directory, naming the file",
          "[results][run_report]") {
  const std::string empty = TempDir("report-empty");
  CHECK_THROWS_WITH(WriteRunReport(empty),
                    Catch::Contains("not a run directory (no metrics.json)"));
  const std::string dir = HandMadeRun("report-bad");
  WriteFile(dir + "/truth.csv", "t_s,x_m,y_m,z_m\n0.0,1.0,nan,2.0\n");
  CHECK_THROWS_WITH(WriteRunReport(dir),
                    Catch::Contains("truth.csv: line 2: \"y_m\" is not a finite number"));
  WriteFile(dir + "/truth.csv", "t_s,x_m,y_m,z_m\n0.0,1.0,2.0,2.0\n");
  WriteFile(dir + "/packets.csv",
            "t_capture_s,modality,window,status,latency_s\n0,camera,0,eaten,\n");
  CHECK_THROWS_WITH(WriteRunReport(dir), Catch::Contains("unknown status \"eaten\""));
  // A cell that would end gnuplot's data block and run as a command.
  WriteFile(dir + "/packets.csv",
            "t_capture_s,modality,window,status,latency_s\n0,EOD,0,delivered,0.01\n"
            "0,system('touch x'),0,delivered,0.01\n");
  CHECK_THROWS_WITH(WriteRunReport(dir),
                    Catch::Contains("line 2: a modality is 1 to 64 letters, digits, '_' or '-'") ||
                        Catch::Contains("line 3: a modality is"));
  CHECK(!fs::exists(dir + "/report.html"));
}
