// A run's report (DESIGN.md: "plots as PNG beside the CSVs they draw, and
// report.html that shows them"): one HTML page a person reads, drawn from
// the run directory's files alone, so `uavsim report DIR` redraws it after a
// change of style without re-running.
//
// Reads (run directory, sim/run_writer.h): manifest.json, metrics.json,
// truth.csv, estimates.csv, packets.csv, world_top.csv, layout.csv,
// rate_snr.csv, rate_snr_common.csv. A file a run of an older version lacks leaves its figures
// out with a note saying which file is missing.
//
// Writes (each file atomically):
//   rate_snr.png             achievable rate vs SNR, a line per beam
//   rate_snr_common.png      the same over the windows every steering
//                            method estimated (rate_snr_common.csv)
//   report/errors.csv        t_s,method,error_m,east_m,north_m,up_m: each
//                            estimate minus the truth at t_s (truth.csv
//                            interpolated linearly in time)
//   report/windows.csv       window,t_start_s,t_end_s,modality,sent,
//                            delivered,late,lost,in_flight,state: per
//                            alignment window and modality, its messages by
//                            fate (packets.csv's window and status) and
//                            what the edge had of it:
//                              on_time       every message delivered on time
//                              partly        some on time, some late or lost
//                              late          none on time, some late
//                              lost          none arrived (lost or in flight)
//                              none_sent     the node sent nothing
//   report/packets_by_fate.csv  modality,delivered,late,lost,in_flight
//   report/latency.csv       modality,latency_ms,fraction: each arrival's
//                            latency, ascending, with the empirical CDF
//   report/top_view.png      the world from above (world_top.csv shaded by
//                            height), the nodes with their fields of view,
//                            the base station, the true path and each
//                            method's estimates
//   report/error_time.png    error vs time per method, over a strip of the
//                            windows' states per modality
//   report/packets.png       messages per modality by fate (stacked bars)
//   report/latency.png       latency CDF per modality
//   report.html              the figures, the RMSE table (with median and
//                            90th percentile of the errors), reception and
//                            latency per modality, the data-rate table
//                            (raw / pre-processed / compressed, as the
//                            paper's Table II), the scenario's key settings,
//                            where the wall time went (metrics.json
//                            profile_s), and links to every file.
//
// Deterministic for the same files, except that report.html shows the wall
// times (as metrics.json holds them).
#pragma once

#include <string>
#include <vector>

namespace uavsim::results {

struct RunReportOptions {
  std::string gnuplot = "gnuplot";  // the program; searched on PATH unless it contains '/'
};

// Writes the report of the run directory `dir`. Returns one line per figure
// that could not be drawn (gnuplot missing or failing, an input file
// missing); the page says so in the figure's place. Throws
// std::invalid_argument if `dir` lacks metrics.json or manifest.json or they
// or a CSV are malformed (naming the file), std::runtime_error on I/O
// failure.
std::vector<std::string> WriteRunReport(const std::string& dir,
                                        const RunReportOptions& options = {});

}  // namespace uavsim::results
