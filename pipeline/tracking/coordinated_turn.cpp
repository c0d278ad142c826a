#include "pipeline/tracking/coordinated_turn.h"

#include <cmath>

namespace uavsim::pipeline {

// Bar-Shalom et al. Eq. 11.7.1-4 and its derivatives; their series in
// omega dt below kSeries (where the closed forms lose digits to
// cancellation).
void CoordinatedTurn(const Eigen::Matrix<double, 10, 1>& x, double dt,
                     Eigen::Matrix<double, 10, 1>& next, Eigen::Matrix<double, 10, 10>& jacobian) {
  constexpr double kSeries = 1e-2;
  const double vx = x(3), vy = x(4), w = x(9);
  const double wt = w * dt, s = std::sin(wt), c = std::cos(wt);
  double a, b, da, db;  // p_xy += [a -b; b a] v_xy; da, db their d/domega
  if (std::abs(wt) < kSeries) {
    const double x2 = wt * wt;
    a = dt * (1.0 - x2 / 6.0), b = dt * wt * (0.5 - x2 / 24.0);
    da = dt * dt * wt * (-1.0 / 3.0 + x2 / 30.0), db = dt * dt * (0.5 - x2 / 8.0);
  } else {
    const double half = std::sin(wt / 2.0);
    a = s / w, b = 2.0 * half * half / w;  // (1 - cos) / w
    da = (dt * c - a) / w, db = (dt * s - b) / w;
  }
  next = x;
  next(0) = x(0) + a * vx - b * vy;
  next(1) = x(1) + b * vx + a * vy;
  next(2) = x(2) + dt * x(5);
  next(3) = c * vx - s * vy;
  next(4) = s * vx + c * vy;
  next.segment<3>(6).setZero();
  jacobian.setIdentity();
  jacobian(0, 3) = a, jacobian(0, 4) = -b, jacobian(0, 9) = da * vx - db * vy;
  jacobian(1, 3) = b, jacobian(1, 4) = a, jacobian(1, 9) = db * vx + da * vy;
  jacobian(2, 5) = dt;
  jacobian(3, 3) = c, jacobian(3, 4) = -s, jacobian(3, 9) = -dt * (s * vx + c * vy);
  jacobian(4, 3) = s, jacobian(4, 4) = c, jacobian(4, 9) = dt * (c * vx - s * vy);
  for (int i = 6; i < 9; ++i) jacobian(i, i) = 0.0;
}

}  // namespace uavsim::pipeline
