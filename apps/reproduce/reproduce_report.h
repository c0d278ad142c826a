// The artefacts of `uavsim reproduce` (apps/reproduce/reproduce.h) and the report that
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
// trajectories): for "A below B" the difference B - A per seed, judged by
// the rules of apps/reproduce/reproduce_verdict.h (holds, reversed, no effect against
// the artefact's equivalence margin, not resolved, with the seeds a
// comparison not resolved would need), and the claims from their
// comparisons (apps/reproduce/reproduce_claims.h). The claims are the rows
// of the paper's claim table (apps/reproduce/reproduce_claim_table.h), in
// its order, each reading what the artefacts measured.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "apps/reproduce/reproduce.h"
#include "apps/reproduce/reproduce_claims.h"
#include "apps/reproduce/reproduce_verdict.h"
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

// Writes every artefact and the reports. Returns warnings (a figure not
// drawn: gnuplot missing, ...). Throws std::runtime_error when a training's
// or a rate run's files are missing or unreadable, std::logic_error when a row of the claim
// table reads what no artefact measures.
std::vector<std::string> WriteReproduceReport(const ReproduceReportInputs& in);

// Redraws the verdicts of a reproduction folder from what it keeps (a
// folder of docs/paper: claims.csv, the artefact CSVs and report.md) with
// the rules of this binary, no training read or re-run: claims.csv, the
// protocol's rules, the "Verdicts" and "Every comparison" sections of
// report.md and report.html rewritten, a paragraph saying so added, every
// other block kept as it was. The margin fraction is DIR/reproduce.json's
// when it records one. A frame-split verdict whose comparisons claims.csv
// lacks (a report written before them) stays as written and says so.
// Throws core::UsageError naming the file for a missing or malformed file.
void RedrawReproduceReport(const std::string& dir);

}  // namespace uavsim::sim
