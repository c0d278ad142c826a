// A sweep's tables and curves, from its finished points (DESIGN.md "sweep"):
// summary.csv (a row per point), aggregate.csv (a row per setting: mean and
// 95 % confidence interval over the seeds), PNG plots drawn with gnuplot
// from CSVs written beside them, and report.html that shows them. Knows
// nothing of scenarios: the sweep hands it each point's parameter cells and
// run-directory contents, and the axes it should plot against.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/json_io.h"

namespace uavsim::results {

// One grid parameter as the tables show it.
struct SweepParameter {
  std::string name;                 // column name, e.g. "loss", "weather"
  std::vector<std::string> labels;  // the cell text of each of its values, in grid order
};

// One finished grid point.
struct SweepPoint {
  std::string id;                // e.g. "p0007"
  std::vector<int> value_index;  // per parameter: which of its labels
  std::uint64_t seed = 0;
  core::Json metrics;        // the point's metrics.json
  std::string rate_snr_csv;  // the point's rate_snr.csv (snr_db,beam,rate_bps_hz)
};

// A curve family to draw: y against one parameter, over the values listed.
struct SweepAxis {
  // File stem under plots/, e.g. "loss" for rmse_loss.png and
  // delivery_loss.png; not empty, ".", ".." nor holding '/', ',', '"' or
  // control characters; unique among the axes.
  std::string stem;
  std::string x_label;  // with unit, e.g. "Packet loss probability"
  int parameter = 0;    // the parameter that varies along x
  // Which of its values lie on the axis, and where (finite; > 0 if log_x).
  // Other values of that parameter are left out of this plot.
  std::vector<std::pair<int, double>> x_of_value;
  bool log_x = false;
};

struct SweepReportInputs {
  std::string title;  // the sweep's name, for plot titles
  std::vector<SweepParameter> parameters;
  std::vector<SweepPoint> points;  // every point of the grid, in grid order
  std::vector<SweepAxis> axes;
};

// Writes into `dir` (which exists; atomically, file by file):
//
//  summary.csv    a row per point, in the given order: point, one column per
//                 parameter (its label), seed, then the metric columns
//                   rmse_<method>        metrics.json rmse_m (null = missing)
//                   coverage_<method>    estimated_windows.<method> / windows:
//                                        the share of windows its RMSE covers
//                   delivery_<modality>  packets_delivered / packets_sent
//                                        (missing when nothing was sent)
//                   gospa_<method>       gospa.methods.<method>.rms_m (several
//                                        targets or a multi-target method)
//                   rate_<beam>_<snr>dB  rate_snr.csv, SNR with trailing
//                                        zeros trimmed ("rate_ekf_-10dB")
//                 methods and modalities sorted by name over all points,
//                 beams in first-seen order, SNRs ascending.
//  aggregate.csv  a row per setting (distinct value_index, in order of first
//                 appearance): each parameter, seeds (its points), then for
//                 every metric column <col>_mean and <col>_ci95 (the half-
//                 width t_{0.975,n-1} s / sqrt(n) over the n points having a
//                 value; ci95 empty for n < 2, mean for n = 0).
//  plots/         per axis with >= 2 x values present: rmse_<stem>,
//                 coverage_<stem>, delivery_<stem> and gospa_<stem> (mean with 95 % error bars, a
//                 line per method or modality and combination of the other parameters, named like
//                 "uavloc; weather=fog 100 m": the other parameters that vary, ", " made "; " as in
//                 any cell); per setting k: rate_snr_<kkk> (rate vs SNR, a line per beam). Each a
//                 long CSV "x,y,ci95,series" beside its PNG. Small multiples
//                 (results/panel_plot.h), each a long CSV "x,y,ci95,series,panel" beside its PNG:
//                 per axis with >= 2 x values panels_rmse_<stem>, panels_coverage_<stem> and
//                 panels_delivery_<stem>, a panel per combination of the
//                 other parameters that vary ("weather=fog 100 m"; "" if
//                 none does), a series per method or modality with a value
//                 in that panel, a row per axis value that has a setting
//                 (RMSE on a log y axis when it spans a factor of 20);
//                 panels_rate_snr, a panel per setting (the parameters that
//                 vary, "loss=0.1; weather=clear", or all if none does), a
//                 series per beam, a row per SNR.
//  report.html    written last: the sweep's name, what varied (parameters
//                 and values, seeds per setting, points), the small
//                 multiples with captions (a plot not drawn shows why), per
//                 setting tables of RMSE, coverage and delivery as
//                 "mean ± ci95", links to summary.csv, aggregate.csv and each
//                 figure's CSV; images and links by relative path.
//
// Numbers have 6 decimals; a missing value is an empty cell. The CSVs are
// plain (no quoting): in every text cell ',' becomes ';', '"' becomes '\''
// and control characters spaces. Same inputs, same bytes.
//
// Returns one line per plot that could not be drawn (gnuplot missing or
// failing, nothing to draw), whose CSV is written all the same. Throws
// std::invalid_argument for inconsistent inputs (a value_index of the wrong
// size or out of range, a bad axis, two columns of the same name, a
// malformed rate_snr.csv), before writing anything, and std::runtime_error
// on I/O failure.
std::vector<std::string> WriteSweepReport(const std::string& dir, const SweepReportInputs& in);

// The two-sided 95 % quantile of Student's t with `dof` >= 1 degrees of
// freedom (t_{0.975, dof}); throws std::invalid_argument for dof < 1.
double StudentT975(int dof);
// The p-quantile of Student's t with `dof` >= 1 degrees of freedom, p in
// (0, 1) (StudentT975(d) is StudentTQuantile(d, 0.975)); throws
// std::invalid_argument otherwise.
double StudentTQuantile(int dof, double p);

}  // namespace uavsim::results
