// Several targets served at once (issue 46): the base station points one
// beam at each position it has (one RF chain per beam), splits its power
// equally over the B beams, and serves target k with the beam s(k)
// assigned to it (or none):
//   SINR_k = |h_k^H f_s(k)|^2 / (B / SNR + sum_{j != s(k)} |h_k^H f_j|^2)
//   R_k    = log2(1 + SINR_k) bit/s/Hz (0 for a target no beam serves),
//   sum rate sum_k R_k,
// with h_k target k's channel (channel/beam_channel.h), f_j the unit-norm
// beam steered at position j (channel/beamformer.h: SteeredBeam) and SNR
// as in channel/beamformer.h (the whole power on one beam over the noise).
// The other beams' gains at target k are their leakage through the UPA's
// pattern. With one beam and one target this is RateBpsHz(snr, gain).
//
// Which beam serves which target: the optimal assignment of targets to
// beams by distance (pipeline-independent: the scorer passes it in); the
// base station is taken to know which of its tracks carries which UAV's
// data (the best case of that association).
//
// Determinism: the channels draw from the scorer's own stream (used by
// path_model "clusters").
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "channel/base_station_config.h"
#include "channel/beam_channel.h"
#include "channel/path_oracle.h"
#include "core/rng.h"

namespace uavsim::channel {

// Target k's received beam gains: its own beam's and the sum of the others'.
struct ServedGains {
  bool served = false;
  double signal = 0.0;        // |h_k^H f_s(k)|^2
  double interference = 0.0;  // sum_{j != s(k)} |h_k^H f_j|^2
};

// h: each target's channel; f: the beams (unit norm); served_by[k]: the
// beam serving target k, or -1. Throws std::invalid_argument for sizes
// that differ or an index out of range.
std::vector<ServedGains> MultiBeamGains(const std::vector<Eigen::VectorXcd>& h,
                                        const std::vector<Eigen::VectorXcd>& f,
                                        const std::vector<int>& served_by);

// R_k above for B = beams (>= 1); 0 when not served.
double SinrRateBpsHz(double snr_db, int beams, const ServedGains& g);

// What one method points and whom each beam serves.
struct MethodBeams {
  std::vector<Eigen::Vector3d> positions_m;  // a beam per position (world ENU)
  std::vector<int> served_by;                // per target: index into positions_m, or -1
};

// The run-long mean rate of each target and the sum rate, per beam set
// ("perfect": a beam at each target's true position; then each method's),
// over an SNR grid.
class MultiBeamScorer {
 public:
  // target_ids: in scenario order; methods: the beam-steering methods.
  MultiBeamScorer(const BaseStationConfig& config, double rain_db_per_km,
                  std::vector<std::string> target_ids, std::vector<std::string> methods,
                  std::vector<double> snr_db, core::RngStream rng);

  // One window: every target's true position, and what each method points
  // (a method absent from the map points nothing: every target 0).
  void AddWindow(const std::vector<Eigen::Vector3d>& targets_m,
                 const std::map<std::string, MethodBeams>& beams, const PathOracle& world);

  // rate_snr_targets.csv: "snr_db,beam,target,rate_bps_hz", per beam set
  // (perfect first, then the methods in order), per SNR ascending, each
  // target (scenario order) then "sum"; 2 and 6 decimals.
  std::string Csv() const;
  // Mean sum rate of a beam set at snr_db()[i] (0 without windows).
  double MeanSumRate(const std::string& beam, std::size_t i) const;
  const std::vector<double>& snr_db() const { return snr_db_; }
  std::uint64_t windows() const { return windows_; }

 private:
  void Score(const std::string& beam, const std::vector<Eigen::Vector3d>& targets_m,
             const MethodBeams& b);

  BeamChannel channel_;
  std::vector<std::string> target_ids_, methods_;
  std::vector<double> snr_db_;
  core::RngStream rng_;
  std::vector<Eigen::VectorXcd> h_;  // this window's channels, per target
  // beam set -> [target (then sum)][snr] summed rates
  std::map<std::string, std::vector<std::vector<double>>> sums_;
  std::uint64_t windows_ = 0;
};

}  // namespace uavsim::channel
