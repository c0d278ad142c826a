#include "channel/multi_beam.h"

#include <cmath>
#include <stdexcept>

#include "channel/beamformer.h"

namespace uavsim::channel {
std::vector<ServedGains> MultiBeamGains(const std::vector<Eigen::VectorXcd>& h,
                                        const std::vector<Eigen::VectorXcd>& f,
                                        const std::vector<int>& served_by) {
  if (served_by.size() != h.size())
    throw std::invalid_argument("MultiBeamGains: " + std::to_string(served_by.size()) +
                                " assignments for " + std::to_string(h.size()) + " targets");
  std::vector<ServedGains> out(h.size());
  for (std::size_t k = 0; k < h.size(); ++k) {
    const int s = served_by[k];
    if (s >= static_cast<int>(f.size()))
      throw std::invalid_argument("MultiBeamGains: beam " + std::to_string(s) + " of " +
                                  std::to_string(f.size()));
    out[k].served = s >= 0;
    for (std::size_t j = 0; j < f.size(); ++j) {
      const double g = BeamGain(h[k], f[j]);
      if (static_cast<int>(j) == s)
        out[k].signal = g;
      else
        out[k].interference += g;
    }
  }
  return out;
}

double SinrRateBpsHz(double snr_db, int beams, const ServedGains& g) {
  if (!g.served) return 0.0;
  const double snr = std::pow(10.0, snr_db / 10.0);
  return std::log2(1.0 + g.signal / (static_cast<double>(beams) / snr + g.interference));
}

MultiBeamScorer::MultiBeamScorer(const BaseStationConfig& config, double rain_db_per_km,
                                 std::vector<std::string> target_ids,
                                 std::vector<std::string> methods, std::vector<double> snr_db,
                                 core::RngStream rng)
    : channel_(config, rain_db_per_km),
      target_ids_(std::move(target_ids)),
      methods_(std::move(methods)),
      snr_db_(std::move(snr_db)),
      rng_(rng) {
  const std::vector<std::vector<double>> zero(target_ids_.size() + 1,
                                              std::vector<double>(snr_db_.size(), 0.0));
  sums_["perfect"] = zero;
  for (const std::string& m : methods_) sums_[m] = zero;
}

void MultiBeamScorer::Score(const std::string& beam, const std::vector<Eigen::Vector3d>& targets_m,
                            const MethodBeams& b) {
  const Eigen::Vector3d& bs = channel_.config().position_m;
  std::vector<Eigen::VectorXcd> f;
  for (const Eigen::Vector3d& p : b.positions_m) f.push_back(SteeredBeam(channel_.upa(), bs, p));
  std::vector<int> served = b.served_by;
  served.resize(targets_m.size(), -1);
  const std::vector<ServedGains> gains = MultiBeamGains(h_, f, served);
  auto& sums = sums_.at(beam);
  const int beams = std::max<int>(1, static_cast<int>(f.size()));
  for (std::size_t i = 0; i < snr_db_.size(); ++i)
    for (std::size_t k = 0; k < gains.size(); ++k) {
      const double r = SinrRateBpsHz(snr_db_[i], beams, gains[k]);
      sums[k][i] += r;
      sums[gains.size()][i] += r;
    }
}

void MultiBeamScorer::AddWindow(const std::vector<Eigen::Vector3d>& targets_m,
                                const std::map<std::string, MethodBeams>& beams,
                                const PathOracle& world) {
  if (targets_m.size() != target_ids_.size())
    throw std::invalid_argument("MultiBeamScorer: " + std::to_string(targets_m.size()) +
                                " positions for " + std::to_string(target_ids_.size()) +
                                " targets");
  h_.resize(targets_m.size());
  for (std::size_t k = 0; k < targets_m.size(); ++k) {
    DownlinkChannel c;
    channel_.RealizeInto(targets_m[k], world, &rng_, &c);
    h_[k] = std::move(c.h);
  }
  MethodBeams perfect;
  perfect.positions_m = targets_m;
  for (std::size_t k = 0; k < targets_m.size(); ++k)
    perfect.served_by.push_back(static_cast<int>(k));
  Score("perfect", targets_m, perfect);
  for (const std::string& m : methods_) {
    const auto it = beams.find(m);
    Score(m, targets_m, it == beams.end() ? MethodBeams{} : it->second);
  }
  ++windows_;
}

double MultiBeamScorer::MeanSumRate(const std::string& beam, std::size_t i) const {
  if (windows_ == 0) return 0.0;
  return sums_.at(beam).back().at(i) / static_cast<double>(windows_);
}

std::string MultiBeamScorer::Csv() const {
  std::string out = "snr_db,beam,target,rate_bps_hz\n";
  if (windows_ == 0) return out;
  const double n = static_cast<double>(windows_);
  std::vector<std::string> order{"perfect"};
  order.insert(order.end(), methods_.begin(), methods_.end());
  for (const std::string& beam : order) {
    const auto& sums = sums_.at(beam);
    for (std::size_t i = 0; i < snr_db_.size(); ++i)
      for (std::size_t k = 0; k < sums.size(); ++k)
        out += FixedDecimal(snr_db_[i], 2) + "," + beam + "," +
               (k < target_ids_.size() ? target_ids_[k] : std::string("sum")) + "," +
               FixedDecimal(sums[k][i] / n, 6) + "\n";
  }
  return out;
}

}  // namespace uavsim::channel
