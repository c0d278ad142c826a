// `uavsim reproduce` (issue 21): the verdicts' statistics against closed
// forms, the plan's shape, and the command end to end at toy size: every
// artefact, a verdict per claim recomputed from the trainings' own reports,
// a SIGTERM that keeps finished trainings, a resume, and a deterministic
// report.
#include <signal.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "apps/reproduce/reproduce.h"
#include "apps/reproduce/reproduce_report.h"
#include "core/json_io.h"
#include "pipeline/variants.h"
#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::core::Json;
using uavsim::sim::CompareSeeds;
using uavsim::sim::MakeReproducePlan;
using uavsim::sim::ReproduceOptions;
using uavsim::sim::ReproducePlan;
using uavsim::sim::SeedComparison;
using uavsim::sim::SummariseSeeds;
using uavsim::testing::Background;
using uavsim::testing::ReadFile;
using uavsim::testing::RunCli;
using uavsim::testing::TempDir;

namespace {

const std::string kDefault = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/default.json";
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// t_{0.975} for 1 and 2 degrees of freedom (tables).
constexpr double kT1 = 12.706204736;
constexpr double kT2 = 4.302652730;

std::vector<std::vector<std::string>> CsvRows(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(ReadFile(path));
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

std::size_t FinishedTrainings(const std::string& dir) {
  std::size_t n = 0;
  std::error_code ec;
  if (!fs::is_directory(dir + "/models", ec)) return 0;
  // A folder whose name starts with '.' is a staging folder: a killed
  // invocation leaves it and the next one removes it, so it is not finished.
  for (const auto& e : fs::directory_iterator(dir + "/models", ec))
    n += e.path().filename().string()[0] != '.' &&
         fs::is_regular_file(e.path() / "training_report.json");
  return n;
}

}  // namespace

TEST_CASE("Reproduce: seed statistics and verdicts against closed forms", "[sim][reproduce]") {
  const auto s = SummariseSeeds({1.0, 2.0, 3.0, kNaN});
  CHECK(s.n == 3);
  CHECK(s.mean == Approx(2.0));
  CHECK(s.ci95 == Approx(kT2 * 1.0 / std::sqrt(3.0)));  // sd 1
  const auto two = SummariseSeeds({4.0, 6.0});
  CHECK(two.ci95 == Approx(kT1 * std::sqrt(2.0) / std::sqrt(2.0)));
  CHECK(std::isnan(SummariseSeeds({5.0}).ci95));
  CHECK(SummariseSeeds({kNaN}).n == 0);

  // Differences 1.0, 1.1, 0.9: mean 1, sd 0.1, half-width 0.248.
  const SeedComparison holds = CompareSeeds("a below b", {1, 1, 1}, {2.0, 2.1, 1.9});
  CHECK(holds.diff.mean == Approx(1.0));
  CHECK(holds.diff.sd == Approx(0.1));
  CHECK(holds.diff.ci95 == Approx(kT2 * 0.1 / std::sqrt(3.0)));
  // A missing value drops its seed (the verdicts: reproduce_verdict_test).
  CHECK(CompareSeeds("", {1, kNaN}, {3, 0}).diff.n == 1);
  CHECK(CompareSeeds("", {kNaN}, {kNaN}).diff.n == 0);
}

TEST_CASE("Reproduce: the plan trains every variant the artefacts need, encoders first",
          "[sim][reproduce]") {
  const uavsim::sim::Scenario scenario;  // z = 16
  for (const bool quick : {false, true}) {
    INFO("quick " << quick);
    ReproduceOptions o;
    o.quick = quick;
    const ReproducePlan plan = MakeReproducePlan(scenario, o);
    CHECK(plan.seeds == (quick ? 2 : 3));
    CHECK(plan.latent_dims == std::vector<int>{4, 16, 64});
    const std::size_t z = plan.latent_dims.size();
    // Per seed: paper, raw and mlp at every z; paper by frame; the two
    // Tab. IV mixes; 14 variants on the paper's encoders, 3 on raw's.
    CHECK(plan.arms.size() == static_cast<std::size_t>(plan.seeds) * (3 * z + 3 + 14 + 3));
    std::set<std::string> ids, variants;
    for (std::size_t i = 0; i < plan.arms.size(); ++i) {
      const auto& a = plan.arms[i];
      INFO(a.id);
      CHECK(ids.insert(a.id).second);
      variants.insert(a.variant);
      const auto* v = uavsim::pipeline::FindVariant(a.variant);
      REQUIRE(v != nullptr);
      CHECK(a.set == uavsim::sim::EpisodeSetName(v->raw_modalities));
      // The edge network only at the scenario's z.
      if (a.edge) CHECK(a.latent_dim == 16);
      if (a.encoders.empty()) continue;
      // Its encoders: an earlier arm of the same seed and z whose nodes send
      // the same latents, with an edge network of its own.
      bool found = false;
      for (std::size_t j = 0; j < i; ++j) {
        const auto& e = plan.arms[j];
        if (e.id != a.encoders) continue;
        found = true;
        CHECK(e.seed == a.seed);
        CHECK(e.latent_dim == a.latent_dim);
        CHECK(e.encoders.empty());
        CHECK(uavsim::pipeline::SameNodes(*uavsim::pipeline::FindVariant(e.variant), *v));
      }
      CHECK(found);
    }
    // Every variant the paper's Sec. VI names.
    for (const auto& v : uavsim::pipeline::Variants()) CHECK(variants.count(v.name) == 1);
  }
}

TEST_CASE("Reproduce: --seeds K adds seeds to a plan, the trained ones unchanged",
          "[sim][reproduce]") {
  const uavsim::sim::Scenario scenario;
  ReproduceOptions three, five;
  five.seeds = 5;
  const ReproducePlan a = MakeReproducePlan(scenario, three), b = MakeReproducePlan(scenario, five);
  CHECK(b.seeds == 5);
  // Seeds 1-3 of the five-seed plan are the three-seed plan's trainings, so
  // a folder of three seeds keeps them and trains seeds 4 and 5 only.
  std::set<std::string> ids;
  for (const auto& arm : b.arms) ids.insert(arm.id);
  for (const auto& arm : a.arms) CHECK(ids.count(arm.id) == 1);
  CHECK(b.arms.size() * 3 == a.arms.size() * 5);
  CHECK(b.equivalence_fraction == a.equivalence_fraction);
}

TEST_CASE("CLI: reproduce refuses bad input with one line and exit 2", "[sim][reproduce]") {
  const std::string dir = TempDir("reproduce-bad");
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"reproduce", "--scenario", dir + "/missing.json"},
        std::vector<std::string>{"reproduce", "--seeds", "0"},
        std::vector<std::string>{"reproduce", "--episodes", "2"},
        std::vector<std::string>{"reproduce", "--jobs", "0"},
        std::vector<std::string>{"reproduce", "something"},
        std::vector<std::string>{"reproduce", "--scenario", kDefault, "--set", "/nope=1"}}) {
    const auto r = RunCli(args);
    INFO(args[1] << " " << args[2 % args.size()] << ": " << r.err);
    CHECK(r.exit_code == 2);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  }
  CHECK(fs::is_empty(dir));
}

TEST_CASE(
    "CLI: reproduce --quick writes every artefact with its verdicts, keeps finished trainings on "
    "SIGTERM and resumes",
    "[sim][reproduce][kill][slow]") {
  const std::string dir = TempDir("reproduce-quick");
  const std::string out = dir + "/r";
  const std::vector<std::string> args = {"reproduce", "--scenario", kDefault, "--quick",
                                         "--jobs",    "2",          "--out",  out};
  // Every model folder is whole (committed at once) or absent.
  const auto whole_models = [&] {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(out + "/models", ec)) {
      const std::string name = e.path().filename().string();
      if (name[0] == '.') continue;  // a staging folder: the next command's to remove
      INFO(name);
      for (const char* f : {"training_report.json", "model.json", "checksums.sha256"})
        CHECK(fs::is_regular_file(e.path() / f));
    }
  };
  {
    // SIGKILL to the whole process group at moments drawn over the first
    // 45 s of each invocation (the episode sets, their files, the first
    // trainings); each next invocation resumes.
    std::mt19937_64 rng(21);
    std::uniform_real_distribution<double> moment(1.0, 45.0);
    std::vector<std::string> quiet = args;
    quiet.push_back("--quiet");
    for (int k = 0; k < 3; ++k) {
      const double at_s = moment(rng);
      INFO("kill " << k << " at " << at_s << " s");
      Background run(quiet, dir + "/kill" + std::to_string(k));
      std::this_thread::sleep_for(std::chrono::duration<double>(at_s));
      kill(-run.pid(), SIGKILL);
      CHECK(run.Wait() == 128 + SIGKILL);
      whole_models();
      CHECK_FALSE(fs::exists(out + "/report.md"));
    }
  }
  std::size_t before_term = 0;  // finished before the SIGTERMed invocation
  {
    // Killed once a few trainings are done: exit 130 within seconds, only
    // whole model folders left.
    std::vector<std::string> quiet = args;
    quiet.push_back("--quiet");
    Background run(quiet, dir + "/log");
    const std::size_t before = before_term = FinishedTrainings(out);
    REQUIRE(run.WaitFor([&] { return FinishedTrainings(out) >= before + 3; }, 900.0));
    kill(run.pid(), SIGTERM);
    REQUIRE((run.WaitFor([] { return false; }, 30.0) || run.Ended()));
    CHECK(run.Wait() == 130);
    whole_models();
    CHECK_FALSE(fs::exists(out + "/report.md"));
  }
  const std::size_t kept = FinishedTrainings(out);
  CHECK(kept >= 3);
  CHECK(kept < 58);

  const auto r = RunCli(args);
  INFO(r.out << r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.out.find("58 trainings (" + std::to_string(kept) + " already done") != std::string::npos);
  CHECK(FinishedTrainings(out) == 58);
  // What the killed invocations staged is gone.
  for (const auto& e : fs::recursive_directory_iterator(out)) {
    const std::string name = e.path().filename().string();
    INFO(e.path());
    CHECK(name.find(".partial") == std::string::npos);
    CHECK(name.find(".tmp-") == std::string::npos);
  }

  // One CSV and one PNG per artefact.
  const std::vector<std::string> artefacts = {"fig07_camera_z",
                                              "fig08_lidar_z",
                                              "fig09_radar_z",
                                              "table2_data_rates",
                                              "table3_flops",
                                              "fig10a_modalities_preprocessed",
                                              "fig10b_modalities_raw",
                                              "table4_camera_preprocessing",
                                              "fig11a_temporal_preprocessed",
                                              "fig11b_temporal_raw",
                                              "fig12_alignment",
                                              "fig13_fusion_modules",
                                              "fig14_fusion_baselines",
                                              "fig15_rate_snr"};
  std::map<std::string, std::string> csvs;
  for (const std::string& a : artefacts) {
    INFO(a);
    const auto rows = CsvRows(out + "/" + a + ".csv");
    CHECK(rows.size() >= 2);
    csvs[a] = ReadFile(out + "/" + a + ".csv");
    CHECK(ReadFile(out + "/" + a + ".png").substr(1, 3) == "PNG");
  }
  // Figs. 7-9 draw the information limit beside the schemes: the paper
  // arm's decoder on the observations holding the target and their centroid.
  for (const char* f : {"fig07_camera_z", "fig08_lidar_z", "fig09_radar_z"}) {
    INFO(f);
    int centroid = 0, on_target = 0;
    for (const auto& row : CsvRows(out + "/" + f + "_limit.csv")) {
      if (row[1] == "centroid on target") {
        ++centroid;
        CHECK(std::stod(row[2]) >= 0.0);
      }
      if (row[1] == "IB on target") ++on_target;
    }
    CHECK(centroid == 3);  // one per latent size of the quick plan
    CHECK(on_target == 3);
    CHECK(ReadFile(out + "/" + f + ".csv").find("on target") == std::string::npos);
  }
  // Tab. IV: the four cases with the paper's values; Fig. 15: the perfect
  // beam and one per subset, each at every SNR of the grid.
  const auto t4 = CsvRows(out + "/table4_camera_preprocessing.csv");
  REQUIRE(t4.size() == 5);
  CHECK(t4[1][0] == "no modality");
  CHECK(t4[4][5] == "0.0223");
  const auto f15 = CsvRows(out + "/fig15_rate_snr.csv");
  CHECK(f15.size() == 1 + 8 * 21);  // -10 .. 30 dB in 2 dB steps
  for (std::size_t i = 1; i < f15.size(); ++i) CHECK(std::stod(f15[i][2]) >= 0.0);

  // Every claim has a verdict; one recomputed from the trainings' reports:
  // Fig. 14, UAVLoc below early fusion on all modalities, seed by seed.
  const auto claims = CsvRows(out + "/claims.csv");
  REQUIRE(claims.size() > 30);
  std::set<std::string> artefact_names;
  bool checked = false;
  for (std::size_t i = 1; i < claims.size(); ++i) {
    const auto& c = claims[i];
    REQUIRE(c.size() == 15);
    artefact_names.insert(c[0]);
    CHECK(
        (c[3] == "holds" || c[3] == "does not hold" || c[3] == "not resolved" || c[3] == "mixed"));
    if (c[6] != "UAVLoc below early fusion; all") continue;
    double sum = 0.0;
    for (int s = 1; s <= 2; ++s) {
      const auto rmse = [&](const std::string& arm, const std::string& method) {
        return uavsim::core::LoadJsonFile(out + "/models/" + arm + "-z16-s" + std::to_string(s) +
                                          "/training_report.json")["test"][method]["all"]["rmse_m"]
            .get<double>();
      };
      sum += rmse("early_fusion", "early_fusion") - rmse("paper", "uavloc");
    }
    CHECK(std::stod(c[7]) == Approx(sum / 2.0).margin(1e-5));
    CHECK(c[9] == "2");
    checked = true;
  }
  CHECK(checked);
  for (const char* a :
       {"Fig. 7", "Fig. 8", "Fig. 9", "Table II", "Table III", "Fig. 10a", "Fig. 10b", "Table IV",
        "Fig. 11a", "Fig. 11b", "Fig. 12", "Fig. 13", "Fig. 14", "Fig. 15"})
    CHECK(artefact_names.count(a) == 1);
  // Every training stage against the plan's budget, recounted from the
  // trainings' own reports and the plan record: its epochs, best epoch,
  // cap and patience, and whether patience had run out when it stopped.
  {
    const Json plan = uavsim::core::LoadJsonFile(out + "/reproduce.json");
    const auto rows = CsvRows(out + "/trainings.csv");
    REQUIRE(rows.size() >= 2);
    CHECK(rows[0] == std::vector<std::string>{"model", "stage", "epochs", "best_epoch",
                                              "max_epochs", "patience", "plateau"});
    std::size_t stages = 0, reached = 0;
    for (const auto& e : fs::directory_iterator(out + "/models")) {
      if (e.path().filename().string()[0] == '.') continue;
      const Json r = uavsim::core::LoadJsonFile((e.path() / "training_report.json").string());
      for (const Json& st : r["stages"]) {
        ++stages;
        const std::string name = st["name"];
        const bool one = name == "camera" || name == "lidar" || name == "radar";
        const int cap = plan["training"][one ? "stage1_max_epochs" : "stage2_max_epochs"];
        const int patience = plan["training"][one ? "stage1_patience" : "stage2_patience"];
        const int epochs = st["epochs"], best = st["best_epoch"];
        CHECK(epochs <= cap);
        const bool plateau = epochs - best >= patience;
        reached += plateau;
        const std::string id = e.path().filename().string();
        const auto row = std::find_if(rows.begin(), rows.end(),
                                      [&](const auto& c) { return c[0] == id && c[1] == name; });
        INFO(id << " " << name);
        REQUIRE(row != rows.end());
        CHECK((*row)[2] == std::to_string(epochs));
        CHECK((*row)[3] == std::to_string(best));
        CHECK((*row)[4] == std::to_string(cap));
        CHECK((*row)[5] == std::to_string(patience));
        CHECK((*row)[6] == (plateau ? "yes" : "no"));
      }
    }
    CHECK(rows.size() == stages + 1);
    CHECK(ReadFile(out + "/report.md")
              .find(std::to_string(reached) + " of " + std::to_string(stages) +
                    " training stages reached their validation plateau") != std::string::npos);
  }
  // The frame split's model was trained on the frame split.
  CHECK(uavsim::core::LoadJsonFile(
            out + "/models/paper-z16-s1-frame/training_report.json")["split"] == "frame");

  // The reports show every figure and the verdicts.
  const std::string md = ReadFile(out + "/report.md");
  CHECK(md.find("## Verdicts") != std::string::npos);
  const std::string html = ReadFile(out + "/report.html");
  for (const std::string& a : artefacts) {
    if (a == "table2_data_rates" || a == "table3_flops" || a == "table4_camera_preprocessing" ||
        a.rfind("fig", 0) == 0) {
      CHECK(md.find("(" + a + ".png)") != std::string::npos);
      CHECK(html.find("src=\"" + a + ".png\"") != std::string::npos);
    }
  }

  // Redrawn from what docs/paper keeps (the CSVs and report.md, no model)
  // and the plan record:
  // the same verdicts and report, through the same code (issue 48).
  {
    const std::string kept_dir = dir + "/kept";
    fs::create_directories(kept_dir);
    for (const auto& e : fs::directory_iterator(out))
      if (e.path().extension() == ".csv" || e.path().filename() == "report.md" ||
          e.path().filename() == "reproduce.json")  // the plan record: its margin rule
        fs::copy_file(e.path(), kept_dir + "/" + e.path().filename().string());
    const auto redraw = RunCli({"report", kept_dir, "--quiet"});
    INFO(redraw.err);
    REQUIRE(redraw.exit_code == 0);
    CHECK(ReadFile(kept_dir + "/claims.csv") == ReadFile(out + "/claims.csv"));
    std::string redrawn = ReadFile(kept_dir + "/report.md");
    const std::size_t note = redrawn.find("\n\nVerdicts redrawn by");
    REQUIRE(note != std::string::npos);
    redrawn.erase(note, redrawn.find('\n', note + 2) - note);
    CHECK(redrawn == md);
    // Fig. 10a's frame split is judged from comparisons of its own.
    std::size_t frame_rows = 0;
    for (const auto& c : claims) frame_rows += c.size() > 11 && c[11] == "frame";
    CHECK(frame_rows == 9);
  }

  // Carried to another machine (scripts/carry-reproduction: the finished
  // trainings without weights, but those of the trainings whose encoders
  // others reuse; no episode sets, no data-rate runs) and resumed there:
  // nothing left to train, no episode set simulated or read, the data-rate
  // runs made again, the same artefacts byte for byte.
  const std::string carried = dir + "/carried";
  REQUIRE(std::system(("'" + std::string(UAVSIM_SOURCE_DIR) + "/scripts/carry-reproduction' '" +
                       out + "' '" + carried + "' >/dev/null")
                          .c_str()) == 0);
  {
    std::set<std::string> reused;
    ReproduceOptions quick;
    quick.quick = true;
    const uavsim::sim::Scenario scenario;  // z = 16, as the default scenario's
    for (const auto& a : MakeReproducePlan(scenario, quick).arms)
      if (!a.encoders.empty()) reused.insert(a.encoders);
    REQUIRE(reused.size() == 4);  // paper and raw at z 16, two seeds
    std::size_t models = 0;
    for (const auto& e : fs::directory_iterator(carried + "/models")) {
      const std::string id = e.path().filename().string();
      INFO(id);
      ++models;
      CHECK(fs::is_regular_file(e.path() / "training_report.json"));
      CHECK(fs::is_regular_file(e.path() / "model.json"));
      CHECK(fs::is_regular_file(e.path() / "camera.pt") == (reused.count(id) == 1));
    }
    CHECK(models == 58);
    CHECK_FALSE(fs::exists(carried + "/episodes"));
  }
  std::vector<std::string> resume = args;
  resume[resume.size() - 1] = carried;  // --out
  const auto again = RunCli(resume);
  INFO(again.err);
  REQUIRE(again.exit_code == 0);
  CHECK(again.out.find("(58 already done, 0 now)") != std::string::npos);
  CHECK(fs::is_empty(carried + "/episodes"));
  for (const auto& [a, text] : csvs) {
    INFO(a);
    CHECK(ReadFile(carried + "/" + a + ".csv") == text);
  }

  // Every invocation's wall time, and how it ended (the carried log and
  // the resumed invocation's row).
  const auto log = CsvRows(carried + "/invocations.csv");
  // (An invocation SIGKILLed in the episode sets has no row; one killed
  // in its trainings reads `killed`, with what it finished.)
  REQUIRE(log.size() >= 4);
  CHECK(log[0] == std::vector<std::string>{"started_utc", "wall_s", "jobs", "trained", "ended"});
  const std::size_t n = log.size();
  CHECK(n - 4 <= 3);  // at most one row per SIGKILLed invocation
  std::size_t trained_by_killed = 0;
  for (std::size_t i = 1; i + 3 < n; ++i) {
    CHECK(log[i][4] == "killed");
    trained_by_killed += std::stoul(log[i][3]);
  }
  CHECK(trained_by_killed <= before_term);  // as of their last finished training
  CHECK(log[n - 3][4] == "interrupted");
  CHECK(log[n - 3][3] == std::to_string(kept - before_term));
  CHECK(log[n - 2][4] == "reported");
  CHECK(log[n - 2][3] == std::to_string(58 - kept));
  CHECK(log[n - 1][3] == "0");
  CHECK(ReadFile(carried + "/report.md").find("over " + std::to_string(n - 1) + " invocation(s)") !=
        std::string::npos);

  // Another plan into the same folder is refused.
  const auto other =
      RunCli({"reproduce", "--scenario", kDefault, "--quick", "--episodes", "7", "--out", out});
  CHECK(other.exit_code == 2);
  CHECK(other.err.find(out) != std::string::npos);
}
