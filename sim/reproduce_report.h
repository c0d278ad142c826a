// The artefacts of `uavsim reproduce` (sim/reproduce.h) and the report that
// puts each beside the paper's claim. From DIR/models/<arm>/ (each
// training's training_report.json and test_estimates.csv) and
// DIR/data_rates/z<z>/metrics.json, into DIR:
//
//   fig07_camera_z.csv/png  fig08_lidar_z  fig09_radar_z
//                         each node's IB decoder alone (no fusion) on the
//                         held-out trajectories vs z: IB, MLP, IB without
//                         pre-processing (mean over seeds, 95 % CI)
//   table2_data_rates     KB/s (1 KB = 1000 bytes) and percent of the raw
//                         rate, ours beside the paper's, per modality
//   table3_flops          MFLOPs per module beside the paper's
//   fig10a_modalities_preprocessed, fig10b_modalities_raw
//                         RMSE per modality subset (10a: split by trajectory
//                         and by frame)
//   table4_camera_preprocessing  the four cases of Tab. IV
//   fig11a_temporal_preprocessed, fig11b_temporal_raw
//   fig12_alignment  fig13_fusion_modules  fig14_fusion_baselines
//   fig15_rate_snr        rate vs SNR steered at each subset's estimate
//                         and at the truth, a beam_upa x beam_upa array at
//                         the scenario's base station, line of sight
//   claims.csv            every claim, its comparisons and verdict
//   report.md, report.html
//
// A verdict compares methods seed by seed (they share the seed's held-out
// trajectories): for "A below B" the difference B - A per seed, its mean
// and 95 % CI (Student t over seeds); it holds when the interval lies above
// 0, is reversed when below, else is within noise (one seed: the sign). A
// claim of several comparisons holds when all hold ("most": more than half
// and none reversed), does not hold when none holds, else is mixed.
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "sim/reproduce.h"
#include "sim/scenario.h"

namespace uavsim::sim {

struct ReproduceReportInputs {
  std::string dir;  // DIR, absolute
  const Scenario* scenario = nullptr;
  const ReproducePlan* plan = nullptr;
  bool quick = false;
  std::string command_line;
  std::size_t trained_now = 0;  // trainings this invocation ran
};

// The statistics of the verdicts (the report's rules above).
struct SeedStat {
  double mean = std::numeric_limits<double>::quiet_NaN();
  double ci95 = std::numeric_limits<double>::quiet_NaN();  // half-width; NaN for n < 2
  int n = 0;                                               // finite values
};
// Mean and Student-t 95 % half-width of the finite values (NaN: missing).
SeedStat SummariseSeeds(const std::vector<double>& values);

struct SeedComparison {
  std::string what;
  SeedStat diff;  // worse - better per seed (where both are finite)
  int sign = 0;   // +1 holds, -1 reversed, 0 within noise or no data
};
// "better below worse", seed by seed (index: seed - 1).
SeedComparison CompareSeeds(const std::string& what, const std::vector<double>& better,
                            const std::vector<double>& worse);
// "holds", "does not hold", "mixed" ("not measured" without comparisons);
// `detail` (if not null) says how many comparisons hold.
std::string ClaimVerdict(const std::vector<SeedComparison>& comparisons, bool most,
                         std::string* detail);

// Writes every artefact and the reports. Returns warnings (a figure not
// drawn: gnuplot missing, ...). Throws std::runtime_error when a training's
// files are missing or unreadable.
std::vector<std::string> WriteReproduceReport(const ReproduceReportInputs& in);

}  // namespace uavsim::sim
