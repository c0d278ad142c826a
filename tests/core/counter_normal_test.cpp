#include "core/counter_normal.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <vector>

using uavsim::core::CounterNormal;

namespace {

// The closed-form standard normal CDF and upper tail.
double Phi(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }
double TwoSidedTail(double z) { return std::erfc(z / std::sqrt(2.0)); }

std::vector<double> Draw(std::uint64_t key, std::size_t n, std::uint64_t first = 0) {
  std::vector<double> z(n);
  CounterNormal(key).Fill(first, z.data(), n);
  return z;
}

double Correlation(const double* a, const double* b, std::size_t n) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sa += a[i], sb += b[i];
    saa += a[i] * a[i], sbb += b[i] * b[i], sab += a[i] * b[i];
  }
  const double ma = sa / n, mb = sb / n;
  return (sab / n - ma * mb) / std::sqrt((saa / n - ma * ma) * (sbb / n - mb * mb));
}

std::vector<double> Squares(const std::vector<double>& z) {
  std::vector<double> q(z.size());
  for (std::size_t i = 0; i < z.size(); ++i) q[i] = z[i] * z[i];
  return q;
}

// The Ziggurat's base-layer edge: every |z| beyond it comes from the tail algorithm.
constexpr double kTailEdge = 3.6541528853610088;

}  // namespace

TEST_CASE("CounterNormal: moments match the standard normal", "[core]") {
  const std::size_t n = std::size_t{1} << 22;  // 4M
  const std::vector<double> z = Draw(2024, n);
  double s1 = 0, s2 = 0, s3 = 0, s4 = 0;
  for (double v : z) s1 += v, s2 += v * v, s3 += v * v * v, s4 += v * v * v * v;
  const double m = s1 / n;
  const double var = s2 / n - m * m;
  const double m3 = s3 / n - 3 * m * s2 / n + 2 * m * m * m;
  const double m4 = s4 / n - 4 * m * s3 / n + 6 * m * m * s2 / n - 3 * m * m * m * m;
  const double skewness = m3 / std::pow(var, 1.5), kurtosis = m4 / (var * var);
  // 5 sigma of each estimator's standard error under N(0, 1).
  CHECK(std::abs(m) < 5 * std::sqrt(1.0 / n));
  CHECK(std::abs(var - 1.0) < 5 * std::sqrt(2.0 / n));
  CHECK(std::abs(skewness) < 5 * std::sqrt(6.0 / n));
  CHECK(std::abs(kurtosis - 3.0) < 5 * std::sqrt(24.0 / n));
}

TEST_CASE("CounterNormal: Kolmogorov-Smirnov statistic against the closed-form CDF", "[core]") {
  const std::size_t n = std::size_t{1} << 20;
  for (std::uint64_t key : {std::uint64_t{1}, std::uint64_t{0xfeedULL}}) {
    std::vector<double> z = Draw(key, n);
    std::sort(z.begin(), z.end());
    double d = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double f = Phi(z[i]);
      d = std::max({d, static_cast<double>(i + 1) / n - f, f - static_cast<double>(i) / n});
    }
    INFO("key " << key << ", D = " << d);
    CHECK(d < 1.95 / std::sqrt(static_cast<double>(n)));  // the 0.1% critical value
  }
}

TEST_CASE("CounterNormal: histogram matches the closed-form density (chi-square)", "[core]") {
  // 100 bins of 0.08 over [-4, 4] and the two tails: fine enough to see a
  // wrong wedge or a layer edge out of place.
  const std::size_t n = std::size_t{1} << 22;
  const int bins = 100;
  const double lo = -4.0, width = 0.08;
  std::vector<double> count(bins + 2, 0.0);
  for (double v : Draw(77, n)) {
    const double k = std::floor((v - lo) / width);  // bin 0 and bins + 1 are the tails
    const double b = std::clamp(k + 1.0, 0.0, static_cast<double>(bins + 1));
    count[static_cast<std::size_t>(b)] += 1;
  }
  double chi2 = 0;
  for (int b = 0; b < bins + 2; ++b) {
    const double left = b == 0 ? -INFINITY : lo + (b - 1) * width;
    const double right = b == bins + 1 ? INFINITY : lo + b * width;
    const double expected = n * (Phi(right) - Phi(left));
    chi2 += (count[b] - expected) * (count[b] - expected) / expected;
  }
  // The 0.1% critical value for bins + 1 degrees of freedom (Wilson-Hilferty).
  const double dof = bins + 1, c = 2.0 / (9.0 * dof);
  const double critical = dof * std::pow(1.0 - c + 3.0902 * std::sqrt(c), 3.0);
  INFO("chi2 = " << chi2 << ", critical = " << critical);
  CHECK(chi2 < critical);
}

TEST_CASE("CounterNormal: tail frequencies match the closed form", "[core]") {
  const std::size_t n = std::size_t{1} << 24;  // 16M
  const double edges[] = {3.0, kTailEdge, 4.0, 4.5};
  std::vector<double> z(std::size_t{1} << 16);
  std::size_t beyond[4] = {0, 0, 0, 0}, negative_tail = 0;
  const CounterNormal g(99);
  double largest = 0;
  std::size_t not_finite = 0;
  for (std::size_t first = 0; first < n; first += z.size()) {
    g.Fill(first, z.data(), z.size());
    for (double v : z) {
      not_finite += !std::isfinite(v);
      largest = std::max(largest, std::abs(v));
      for (int e = 0; e < 4; ++e) beyond[e] += std::abs(v) > edges[e];
      negative_tail += v < -kTailEdge;
    }
  }
  for (int e = 0; e < 4; ++e) {
    const double p = TwoSidedTail(edges[e]);
    INFO("P(|z| > " << edges[e] << "): " << beyond[e] << " of " << n << ", expected " << n * p);
    CHECK(std::abs(beyond[e] - n * p) < 5 * std::sqrt(n * p * (1 - p)));
  }
  CHECK(not_finite == 0);
  // The tail is symmetric and unbounded: both signs, and values past r.
  const double half = 0.5 * beyond[1];
  CHECK(std::abs(negative_tail - half) < 5 * std::sqrt(half * 0.5));
  CHECK(largest > 5.0);
}

TEST_CASE("CounterNormal: a value is a pure function of key and index", "[core]") {
  const std::size_t n = 200000;
  const std::vector<double> whole = Draw(5, n);
  const CounterNormal g(5), twin(5);
  // Any block size and start offset gives the same values, including the
  // rare wedge and tail draws (about 1.5% of them).
  for (std::size_t block : {1, 3, 64, 641, 4096}) {
    std::vector<double> part(n);
    for (std::size_t first = 0; first < n; first += block)
      twin.Fill(first, part.data() + first, std::min(block, n - first));
    INFO("block " << block);
    CHECK(part == whole);
  }
  std::size_t tail = 0, differ = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool in_tail = std::abs(whole[i]) > kTailEdge;
    tail += in_tail;
    if (in_tail || i % 997 == 0) differ += g.At(i) != whole[i];
  }
  CHECK(tail > 10);
  CHECK(differ == 0);
  // Floats are the doubles rounded to nearest.
  std::vector<float> f(4096);
  g.Fill(1000, f.data(), f.size());
  std::size_t float_differ = 0;
  for (std::size_t j = 0; j < f.size(); ++j)
    float_differ += f[j] != static_cast<float>(whole[1000 + j]);
  CHECK(float_differ == 0);
  // Indices wrap modulo 2^64.
  double wrap[4];
  g.Fill(~std::uint64_t{0} - 1, wrap, 4);
  CHECK(wrap[0] == g.At(~std::uint64_t{0} - 1));
  CHECK(wrap[1] == g.At(~std::uint64_t{0}));
  CHECK(wrap[2] == whole[0]);
  CHECK(wrap[3] == whole[1]);
  CHECK(g.key() == 5);
}

TEST_CASE("CounterNormal: the stream of key 1 is pinned", "[core]") {
  // Guards stored runs against an accidental change of the stream. The
  // tolerance allows another libm's last bit in the tables.
  const CounterNormal g(1);
  CHECK(g.At(0) == Approx(-0.89347481458996802).margin(1e-12));
  CHECK(g.At(1) == Approx(-0.62352854400507363).margin(1e-12));
  CHECK(g.At(2) == Approx(-0.07195771538018314).margin(1e-12));
  CHECK(g.At(3) == Approx(-0.97919492667500763).margin(1e-12));
  CHECK(g.At(4) == Approx(0.41153776166438116).margin(1e-12));
}

TEST_CASE("CounterNormal: different keys give uncorrelated streams", "[core]") {
  const std::size_t n = std::size_t{1} << 20;
  const double bound = 5.0 / std::sqrt(static_cast<double>(n));
  const std::pair<std::uint64_t, std::uint64_t> pairs[] = {
      {1, 2}, {0, 1}, {12345, 12346}, {1, std::uint64_t{1} << 32}};
  for (const auto& [ka, kb] : pairs) {
    const std::vector<double> a = Draw(ka, n), b = Draw(kb, n);
    INFO("keys " << ka << " and " << kb);
    CHECK(a != b);
    CHECK(std::abs(Correlation(a.data(), b.data(), n)) < bound);
    const std::vector<double> qa = Squares(a), qb = Squares(b);  // dependence beyond linear
    CHECK(std::abs(Correlation(qa.data(), qb.data(), n)) < bound);
    // A stream shifted by one index is no other key's stream either.
    CHECK(std::abs(Correlation(a.data() + 1, b.data(), n - 1)) < bound);
  }
}

TEST_CASE("CounterNormal: adjacent indices are uncorrelated", "[core]") {
  const std::size_t n = std::size_t{1} << 20;
  const std::vector<double> z = Draw(31337, n), q = Squares(z);
  for (std::size_t lag : {1, 2, 3, 256}) {
    const double bound = 5.0 / std::sqrt(static_cast<double>(n - lag));
    INFO("lag " << lag);
    CHECK(std::abs(Correlation(z.data(), z.data() + lag, n - lag)) < bound);
    CHECK(std::abs(Correlation(q.data(), q.data() + lag, n - lag)) < bound);
  }
}
