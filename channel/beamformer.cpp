#include "channel/beamformer.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace uavsim::channel {
namespace {

constexpr double kMinDistanceM = 0.01;

// The unit direction from bs_m to target_m in frame A; broadside when they
// (nearly) coincide.
Eigen::Vector3d DirectionInArray(const Upa& upa, const Eigen::Vector3d& bs_m,
                                 const Eigen::Vector3d& target_m) {
  const Eigen::Vector3d d = target_m - bs_m;
  const double n = d.norm();
  if (n < kMinDistanceM) return Eigen::Vector3d::UnitZ();
  return upa.ToArrayFrame(d / n);
}

// Circular index of the grid point k / size nearest to psi (cycles).
int NearestGridIndex(double psi, int size) {
  const long k = std::lround(psi * size);
  return static_cast<int>(((k % size) + size) % size);
}

// Locale-independent fixed-point text; "-0.00" prints as "0.00".

}  // namespace

Eigen::VectorXcd SteeredBeam(const Upa& upa, const Eigen::Vector3d& bs_m,
                             const Eigen::Vector3d& target_m) {
  Eigen::VectorXcd f;
  SteeredBeamInto(upa, bs_m, target_m, &f);
  return f;
}

void SteeredBeamInto(const Upa& upa, const Eigen::Vector3d& bs_m, const Eigen::Vector3d& target_m,
                     Eigen::VectorXcd* f) {
  upa.SteeringInto(DirectionInArray(upa, bs_m, target_m), f);
  *f /= std::sqrt(static_cast<double>(upa.size()));  // Sec. VI-C: unit-norm f_est
}

double BeamGain(const Eigen::VectorXcd& h, const Eigen::VectorXcd& f) {
  return std::norm(h.dot(f));  // Sec. VI-C: gamma = |h^H f|^2 (Eigen's dot conjugates h)
}

double LosSteeredGain(const Upa& upa, const Eigen::Vector3d& bs_m,
                      const Eigen::Vector3d& estimate_m, const Eigen::Vector3d& truth_m) {
  Eigen::VectorXcd h, f;
  upa.SteeringInto(DirectionInArray(upa, bs_m, truth_m), &h);
  SteeredBeamInto(upa, bs_m, estimate_m, &f);
  return BeamGain(h, f);
}

double RateBpsHz(double snr_db, double gain) {
  return std::log2(1.0 + std::pow(10.0, snr_db / 10.0) * gain);
}

DftCodebook::DftCodebook(const Upa& upa, int oversampling) : upa_(upa) {
  if (oversampling < 1)
    throw std::invalid_argument("DftCodebook: oversampling must be >= 1, got " +
                                std::to_string(oversampling));
  nx_ = oversampling * upa.mx();
  ny_ = oversampling * upa.my();
}

double DftCodebook::psi_x(int kx) const {
  const double p = static_cast<double>(kx) / nx_;
  return p >= 0.5 ? p - 1.0 : p;
}

double DftCodebook::psi_y(int ky) const {
  const double p = static_cast<double>(ky) / ny_;
  return p >= 0.5 ? p - 1.0 : p;
}

DftCodebook::Index DftCodebook::Best(const Eigen::Vector3d& u_A) const {
  const double d = upa_.spacing_wavelengths();
  return {NearestGridIndex(d * u_A.x(), nx_), NearestGridIndex(d * u_A.y(), ny_)};
}

Eigen::VectorXcd DftCodebook::Codeword(Index i) const {
  Eigen::VectorXcd f;
  CodewordInto(i, &f);
  return f;
}

void DftCodebook::CodewordInto(Index i, Eigen::VectorXcd* f) const {
  upa_.SpatialSteeringInto(psi_x(i.kx), psi_y(i.ky), f);
  *f /= std::sqrt(static_cast<double>(upa_.size()));
}

void DftCodebook::BeamAtInto(const Eigen::Vector3d& bs_m, const Eigen::Vector3d& target_m,
                             Eigen::VectorXcd* f) const {
  CodewordInto(Best(DirectionInArray(upa_, bs_m, target_m)), f);
}

std::vector<double> SnrGridDb(double from_db, double to_db, double step_db) {
  if (!(step_db > 0.0) || !(from_db <= to_db))
    throw std::invalid_argument("SnrGridDb: need step_db > 0 and from_db <= to_db");
  // Points from the integer index, not by repeated addition, so the grid
  // does not drift.
  const auto n = static_cast<long>(std::floor((to_db - from_db) / step_db + 1e-9));
  std::vector<double> grid;
  grid.reserve(static_cast<std::size_t>(n) + 1);
  for (long i = 0; i <= n; ++i) grid.push_back(from_db + static_cast<double>(i) * step_db);
  return grid;
}

RateSnrAccumulator::RateSnrAccumulator(std::vector<double> snr_db) : snr_db_(std::move(snr_db)) {
  snr_linear_.reserve(snr_db_.size());
  for (double s : snr_db_) snr_linear_.push_back(std::pow(10.0, s / 10.0));
}

void RateSnrAccumulator::AddBeam(const std::string& beam) {
  if (sums_.count(beam)) return;
  order_.push_back(beam);
  sums_[beam].rate.assign(snr_db_.size(), 0.0);
}

void RateSnrAccumulator::Add(const std::string& beam, double gain) {
  if (!(gain >= 0.0) || !std::isfinite(gain))
    throw std::invalid_argument("RateSnrAccumulator: gain of beam \"" + beam +
                                "\" must be finite and >= 0");
  AddBeam(beam);
  Sums& s = sums_[beam];
  for (std::size_t i = 0; i < snr_linear_.size(); ++i)
    s.rate[i] += std::log2(1.0 + snr_linear_[i] * gain);
  s.gain += gain;
  ++s.windows;
}

const RateSnrAccumulator::Sums* RateSnrAccumulator::Find(const std::string& beam) const {
  const auto it = sums_.find(beam);
  return it == sums_.end() ? nullptr : &it->second;
}

std::size_t RateSnrAccumulator::windows(const std::string& beam) const {
  const Sums* s = Find(beam);
  return s ? s->windows : 0;
}

double RateSnrAccumulator::MeanRateBpsHz(const std::string& beam, std::size_t i) const {
  const Sums* s = Find(beam);
  return s && s->windows ? s->rate.at(i) / static_cast<double>(s->windows) : 0.0;
}

double RateSnrAccumulator::MeanGain(const std::string& beam) const {
  const Sums* s = Find(beam);
  return s && s->windows ? s->gain / static_cast<double>(s->windows) : 0.0;
}

std::string RateSnrAccumulator::Csv() const {
  std::string out = "snr_db,beam,rate_bps_hz\n";
  for (const std::string& beam : order_) {
    if (windows(beam) == 0) continue;
    for (std::size_t i = 0; i < snr_db_.size(); ++i)
      out += FixedDecimal(snr_db_[i], 2) + "," + beam + "," +
             FixedDecimal(MeanRateBpsHz(beam, i), 6) + "\n";
  }
  return out;
}

DownlinkScorer::DownlinkScorer(const BaseStationConfig& config, double rain_db_per_km,
                               std::vector<std::string> methods, std::vector<double> snr_db,
                               core::RngStream rng)
    : channel_(config, rain_db_per_km),
      codebook_(channel_.upa(), config.dft_oversampling),
      methods_(std::move(methods)),
      steered_(false),
      dft_(false),
      rng_(rng),
      rates_(std::move(snr_db)) {
  for (const std::string& b : config.beams) {
    if (b == "steered")
      steered_ = true;
    else if (b == "dft")
      dft_ = true;
    else
      throw std::invalid_argument("DownlinkScorer: unknown beam family \"" + b + "\"");
  }
  for (std::size_t i = 0; i < methods_.size(); ++i) {
    const std::string& m = methods_[i];
    if (m == "perfect" || m.rfind("dft_", 0) == 0 ||
        std::find(methods_.begin(), methods_.begin() + i, m) != methods_.begin() + i)
      throw std::invalid_argument("DownlinkScorer: method name \"" + m +
                                  "\" is reserved or repeated");
  }
  if (steered_) {
    rates_.AddBeam("perfect");
    for (const std::string& m : methods_) rates_.AddBeam(m);
  }
  if (dft_) {
    rates_.AddBeam("dft_perfect");
    for (const std::string& m : methods_) rates_.AddBeam("dft_" + m);
  }
}

void DownlinkScorer::AddWindow(const Eigen::Vector3d& true_position_m,
                               const std::map<std::string, Eigen::Vector3d>& estimates,
                               const PathOracle& world) {
  for (const auto& [name, position] : estimates)
    if (std::find(methods_.begin(), methods_.end(), name) == methods_.end())
      throw std::invalid_argument("DownlinkScorer: estimate of unknown method \"" + name + "\"");
  channel_.RealizeInto(true_position_m, world, &rng_, &last_);
  const Eigen::Vector3d& bs = channel_.config().position_m;

  const auto score = [&](const std::string& prefix, const std::string& name,
                         const Eigen::Vector3d* target, bool dft) {
    double gain = 0.0;
    if (target) {
      if (dft)
        codebook_.BeamAtInto(bs, *target, &f_);
      else
        SteeredBeamInto(channel_.upa(), bs, *target, &f_);
      gain = BeamGain(last_.h, f_);
    }
    rates_.Add(prefix + name, gain);
  };
  for (const bool dft : {false, true}) {
    if (dft ? !dft_ : !steered_) continue;
    const std::string prefix = dft ? "dft_" : "";
    score(prefix, "perfect", &true_position_m, dft);
    for (const std::string& m : methods_) {
      const auto it = estimates.find(m);
      score(prefix, m, it == estimates.end() ? nullptr : &it->second, dft);
    }
  }
}

std::string FixedDecimal(double x, int decimals) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::fixed, decimals);
  std::string s(buf, r.ptr);
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

}  // namespace uavsim::channel
