// Downlink beams of the base station's UPA (paper Sec. VI-C), their gain on a
// channel from channel/beam_channel.h, the achievable rate over an SNR grid,
// and the run-long average that becomes rate_snr.csv.
//
//   steered beam   f = a(u_A) / sqrt(Mx My), u_A the unit direction, in the
//                  array frame A (channel/upa.h), from the array centre to a
//                  position (the true one for "perfect", an estimate else)
//   gain           gamma = |h^H f|^2
//   rate           R = log2(1 + SNR gamma) bit/s/Hz, SNR = 10^(snr_db / 10)
//                  as defined by the channel's normalisation
//                  (channel/beam_channel.h)
//   DFT codebook   the best codeword, for a direction, of an oversampled 2-D
//                  DFT codebook (DftCodebook below)
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "channel/base_station_config.h"
#include "channel/beam_channel.h"
#include "channel/path_oracle.h"
#include "channel/upa.h"
#include "core/rng.h"

namespace uavsim::channel {

// The unit-norm beam steered from the array centre bs_m at target_m (world
// ENU, metres). A target within 1 cm of bs_m gets the broadside beam.
Eigen::VectorXcd SteeredBeam(const Upa& upa, const Eigen::Vector3d& bs_m,
                             const Eigen::Vector3d& target_m);
void SteeredBeamInto(const Upa& upa, const Eigen::Vector3d& bs_m, const Eigen::Vector3d& target_m,
                     Eigen::VectorXcd* f);

// gamma = |h^H f|^2. h and f have the same size.
double BeamGain(const Eigen::VectorXcd& h, const Eigen::VectorXcd& f);

// The gain of a line-of-sight channel h = a(u_true) (unit path gain, no
// blockage) with the beam steered from bs_m at estimate_m: |a(u_true)^H f|^2,
// Mx My when the estimate lies on the true direction. Positions world ENU
// (m); a position within 1 cm of bs_m is taken as broadside. What
// `uavsim reproduce` scores Fig. 15 with.
double LosSteeredGain(const Upa& upa, const Eigen::Vector3d& bs_m,
                      const Eigen::Vector3d& estimate_m, const Eigen::Vector3d& truth_m);

// x with `decimals` decimals, locale-independent, never "-0.00" (the
// rate tables' cells).
std::string FixedDecimal(double x, int decimals);

// log2(1 + 10^(snr_db / 10) gain), bit/s/Hz.
double RateBpsHz(double snr_db, double gain);

// Oversampled 2-D DFT codebook of a UPA: (O Mx) x (O My) unit-norm codewords
//   [f_kl]_(m + Mx n) = exp(j 2 pi (m' psi_x(k) + n' psi_y(l))) / sqrt(Mx My),
//   psi_x(k) = k / (O Mx), psi_y(l) = l / (O My), wrapped into [-1/2, 1/2),
// with m', n' the centred element indices of channel/upa.h. f_kl is the
// normalised steering vector of any direction with d u_x = psi_x(k) and
// d u_y = psi_y(l) (d: spacing in wavelengths). With O = 1 and d = 1/2 the
// codewords are orthonormal.
class DftCodebook {
 public:
  struct Index {
    int kx = 0;  // 0 .. O Mx - 1
    int ky = 0;  // 0 .. O My - 1
  };

  // oversampling >= 1; throws std::invalid_argument otherwise.
  DftCodebook(const Upa& upa, int oversampling);

  // The codeword of largest gain |a(u_A)^H f_kl|^2 towards the direction u_A
  // (frame A, unit): the grid point (psi_x, psi_y) nearest to (d u_x, d u_y)
  // in circular distance in each dimension (the Dirichlet kernel falls
  // monotonically over half a grid step).
  Index Best(const Eigen::Vector3d& u_A) const;
  Eigen::VectorXcd Codeword(Index i) const;
  void CodewordInto(Index i, Eigen::VectorXcd* f) const;
  // Codeword(Best(direction from bs_m to target_m)); broadside within 1 cm.
  void BeamAtInto(const Eigen::Vector3d& bs_m, const Eigen::Vector3d& target_m,
                  Eigen::VectorXcd* f) const;

  double psi_x(int kx) const;
  double psi_y(int ky) const;
  int size_x() const { return nx_; }
  int size_y() const { return ny_; }

 private:
  Upa upa_;
  int nx_;
  int ny_;
};

// from_db, from_db + step_db, ... up to to_db (included when it is on the
// grid to within 1e-9 of a step). Throws std::invalid_argument unless
// step_db > 0 and from_db <= to_db.
std::vector<double> SnrGridDb(double from_db, double to_db, double step_db);

// Averages the rate of each beam over a run's windows, at every SNR of a grid:
// mean over windows w of log2(1 + SNR_i gamma_w).
class RateSnrAccumulator {
 public:
  explicit RateSnrAccumulator(std::vector<double> snr_db);

  // Registers a beam name; the CSV lists beams in registration order. Add
  // registers names it has not seen.
  void AddBeam(const std::string& beam);
  // One window's gain of `beam` (gamma >= 0; std::invalid_argument else).
  void Add(const std::string& beam, double gain);

  std::size_t windows(const std::string& beam) const;  // 0 for unknown names
  // Mean rate of `beam` at snr_db()[i] over its windows; 0 without windows.
  double MeanRateBpsHz(const std::string& beam, std::size_t i) const;
  // Mean gamma of `beam` over its windows; 0 without windows.
  double MeanGain(const std::string& beam) const;

  const std::vector<std::string>& beams() const { return order_; }
  const std::vector<double>& snr_db() const { return snr_db_; }

  // rate_snr.csv: header "snr_db,beam,rate_bps_hz", then for each beam with
  // at least one window (registration order) one row per grid SNR
  // (ascending); snr_db with 2 decimals, rate with 6; locale-independent.
  std::string Csv() const;

 private:
  struct Sums {
    std::vector<double> rate;  // per grid SNR
    double gain = 0.0;
    std::size_t windows = 0;
  };
  const Sums* Find(const std::string& beam) const;

  std::vector<double> snr_db_;
  std::vector<double> snr_linear_;
  std::vector<std::string> order_;
  std::map<std::string, Sums> sums_;
};

// What the engine calls once per alignment window: realises the channel at
// the UAV's true position and scores every beam on it.
//
// Beams, in CSV order: with "steered" in config.beams, "perfect" (steered at
// the true position) and one per method (steered at its estimate); with
// "dft", "dft_perfect" and "dft_<method>" (best DFT codeword for the same
// positions). A method without an estimate in a window scores gamma = 0
// there (the base station has nothing to point at), so every beam averages
// over the same windows.
class DownlinkScorer {
 public:
  // methods: localization method names (e.g. {"uavloc", "ekf"}); throws
  // std::invalid_argument for duplicates, "perfect" or names starting with
  // "dft_". rng: the downlink's own stream (used by path_model "clusters").
  DownlinkScorer(const BaseStationConfig& config, double rain_db_per_km,
                 std::vector<std::string> methods, std::vector<double> snr_db, core::RngStream rng);

  // One window. estimates: method name -> its position estimate (world ENU,
  // metres); methods absent from the map score 0, unknown names throw
  // std::invalid_argument.
  void AddWindow(const Eigen::Vector3d& true_position_m,
                 const std::map<std::string, Eigen::Vector3d>& estimates, const PathOracle& world);

  const RateSnrAccumulator& rates() const { return rates_; }
  const BeamChannel& channel() const { return channel_; }
  // The channel of the last window (empty before the first).
  const DownlinkChannel& last_channel() const { return last_; }

 private:
  BeamChannel channel_;
  DftCodebook codebook_;
  std::vector<std::string> methods_;
  bool steered_;
  bool dft_;
  core::RngStream rng_;
  RateSnrAccumulator rates_;
  DownlinkChannel last_;
  Eigen::VectorXcd f_;
};

}  // namespace uavsim::channel
