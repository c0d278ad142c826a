// The interacting multiple model (IMM) estimator's own steps (Blom &
// Bar-Shalom, IEEE Trans. Automatic Control 33(8), 1988; Bar-Shalom, Li &
// Kirubarajan, "Estimation with Applications to Tracking and Navigation",
// 2001, Sec. 11.6.6), shared by the filters that run a bank of mode-matched
// Kalman filters on one state vector (the `ekf` baseline,
// pipeline/baselines/ekf.h, and the anchor filter,
// pipeline/anchored/anchor_filter.h). Imm<N> holds each mode's moments
// (x_j, P_j) and probability mu_j; the filter that owns it supplies the
// transition matrix, the motion models (it predicts each mode in modes()),
// the measurement updates (it updates each mode in modes()) and the modes'
// measurement log-likelihoods. One cycle, in Sec. 11.6.6's steps:
//   1-2. Mix(pi): the mixing probabilities and the mixed initial conditions;
//   3.   (the filter) mode-matched filtering: it predicts every mode, and
//        updates every mode with a measurement, giving each mode's
//        likelihood Lambda_j = N(y_j; 0, S_j);
//   4.   UpdateProbabilities(log Lambda): the mode probabilities;
//   5.   Combined(): the moment-matched estimate (the modes stay as they are).
// The equations are on the methods, one line each.
//
// Units: those of the filter's state (x_j) and their squares (P_j);
// probabilities dimensionless; log-likelihoods natural logarithms of
// densities (only their differences between modes matter).
// Throws std::invalid_argument, naming the sizes, for an empty set of modes
// or a transition matrix or likelihood vector whose size is not the number
// of modes. Nothing else is checked: pi's rows are taken as given (a
// stochastic matrix keeps sum_j mu_j = 1), and a mode j that no probability
// flows into (cbar_j = 0) divides 0 by 0 in Mix, as the equations do.
// Deterministic: no randomness; sums run over the modes in index order
// (mode 0 first) with exactly the operations written on each method. That
// order is part of the contract: the filters' outputs (estimates.csv) depend
// on it to the last bit.
// Thread safety: none (plain value type, copyable).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace uavsim::pipeline {

template <int N>
class Imm {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;
  using Matrix = Eigen::Matrix<double, N, N>;
  // One mode-matched filter's estimate: mean and covariance.
  struct Mode {
    Vector x = Vector::Zero();
    Matrix P = Matrix::Identity();
  };

  Imm() = default;
  // One mode per probability, each at x = 0, P = I. Throws for none.
  explicit Imm(std::vector<double> probabilities) { Reset(Mode{}, std::move(probabilities)); }

  // Every mode at `start`, mu_j = probabilities[j] (taken as given). Throws
  // for none.
  void Reset(const Mode& start, std::vector<double> probabilities) {
    if (probabilities.empty()) throw std::invalid_argument("Imm: needs at least one mode, got 0");
    modes_.assign(probabilities.size(), start);
    mu_ = std::move(probabilities);
  }

  std::size_t size() const { return modes_.size(); }
  const std::vector<Mode>& modes() const { return modes_; }
  // The filter predicts and updates each mode here (same size: do not resize).
  std::vector<Mode>& modes() { return modes_; }
  const std::vector<double>& probabilities() const { return mu_; }

  // Steps 1-2 with pi(i, j) = P{mode j over the coming interval | mode i
  // now}: every mode starts from the mixture of all modes, and mu_j becomes
  // the predicted cbar_j. With one mode nothing is mixed. source_of(modes,
  // i, j) is mode i's estimate as mode j takes it in (modes() as they were
  // before mixing): mode i itself unless the modes' states differ in meaning
  // (unequal-dimension mixing). Throws unless pi is size() x size().
  template <class SourceOf>
  void Mix(const Eigen::MatrixXd& pi, const SourceOf& source_of) {
    const std::size_t n = modes_.size();
    if (static_cast<std::size_t>(pi.rows()) != n || static_cast<std::size_t>(pi.cols()) != n)
      throw std::invalid_argument("Imm::Mix: transition matrix is " + std::to_string(pi.rows()) +
                                  "x" + std::to_string(pi.cols()) + ", expected " +
                                  std::to_string(n) + "x" + std::to_string(n));
    if (n < 2) return;
    const auto at = [](std::size_t k) { return static_cast<Eigen::Index>(k); };
    std::vector<double> c(n, 0.0);
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t i = 0; i < n; ++i)
        c[j] += pi(at(i), at(j)) * mu_[i];  // cbar_j = sum_i pi_ij mu_i
    std::vector<Mode> mixed(n);
    std::vector<Mode> sources;
    sources.reserve(n);
    for (std::size_t j = 0; j < n; ++j) {
      sources.clear();
      for (std::size_t i = 0; i < n; ++i) sources.push_back(source_of(modes_, i, j));
      // mu_{i|j} = pi_ij mu_i / cbar_j;  x0_j = sum_i mu_{i|j} x_i
      Vector x = Vector::Zero();
      for (std::size_t i = 0; i < n; ++i) x += pi(at(i), at(j)) * mu_[i] / c[j] * sources[i].x;
      // P0_j = sum_i mu_{i|j} (P_i + (x_i - x0_j)(x_i - x0_j)^T)
      Matrix P = Matrix::Zero();
      for (std::size_t i = 0; i < n; ++i) {
        const Vector d = sources[i].x - x;
        P += pi(at(i), at(j)) * mu_[i] / c[j] * (sources[i].P + d * d.transpose());
      }
      mixed[j] = {x, P};
    }
    modes_ = std::move(mixed);
    mu_ = std::move(c);  // mu_j <- cbar_j
  }
  void Mix(const Eigen::MatrixXd& pi) {
    Mix(pi, [](const std::vector<Mode>& modes, std::size_t i, std::size_t) { return modes[i]; });
  }

  // Step 4: mu_j <- Lambda_j mu_j / sum_l Lambda_l mu_l, from log Lambda_j
  // taken relative to the largest (no underflow when every likelihood is
  // tiny). A mode may have log Lambda_j = -infinity (its update failed): it
  // gets probability 0. When no mode has a finite largest log-likelihood, or
  // the sum is not positive, the probabilities stay as they were. Throws
  // unless log_likelihood has size() entries.
  void UpdateProbabilities(const std::vector<double>& log_likelihood) {
    const std::size_t n = modes_.size();
    if (log_likelihood.size() != n)
      throw std::invalid_argument(
          "Imm::UpdateProbabilities: " + std::to_string(log_likelihood.size()) +
          " log-likelihoods for " + std::to_string(n) + " modes");
    const double best = *std::max_element(log_likelihood.begin(), log_likelihood.end());
    if (!std::isfinite(best)) return;
    std::vector<double> weight(n);
    double total = 0.0;
    for (std::size_t j = 0; j < n; ++j)
      total += weight[j] = mu_[j] * std::exp(log_likelihood[j] - best);  // Lambda_j cbar_j
    if (!(total > 0.0)) return;
    for (std::size_t j = 0; j < n; ++j) mu_[j] = weight[j] / total;
  }

  // Step 5, the moment-matched mixture:
  //   x = sum_j mu_j x_j,  P = sum_j mu_j (P_j + (x_j - x)(x_j - x)^T).
  Mode Combined() const {
    Mode m;
    m.x.setZero();
    for (std::size_t j = 0; j < modes_.size(); ++j) m.x += mu_[j] * modes_[j].x;
    m.P.setZero();
    for (std::size_t j = 0; j < modes_.size(); ++j) {
      const Vector d = modes_[j].x - m.x;
      m.P += mu_[j] * (modes_[j].P + d * d.transpose());
    }
    return m;
  }

 private:
  std::vector<Mode> modes_;
  std::vector<double> mu_;
};

}  // namespace uavsim::pipeline
