#include "sensors/lidar_coverage.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/physical_constants.h"

namespace uavsim::sensors {
namespace {

using core::kPi;

// Equal-solid-angle cells: row r covers elevations [r d - pi/2, (r+1) d -
// pi/2), split into counts_[r] azimuth cells.
class DirectionCells {
 public:
  explicit DirectionCells(double cell_rad) : d_(cell_rad) {
    rows_ = static_cast<std::size_t>(std::ceil(kPi / d_));
    first_.reserve(rows_ + 1);
    counts_.reserve(rows_);
    std::size_t total = 0;
    for (std::size_t r = 0; r < rows_; ++r) {
      const double el = (static_cast<double>(r) + 0.5) * d_ - kPi / 2.0;
      const auto n = static_cast<std::size_t>(
          std::max(1.0, std::ceil(2.0 * kPi * std::cos(std::min(el, kPi / 2.0)) / d_)));
      first_.push_back(total);
      counts_.push_back(n);
      total += n;
    }
    first_.push_back(total);
  }
  std::size_t size() const { return first_.back(); }
  std::size_t Of(const Eigen::Vector3f& dir) const {
    const double x = dir.x(), y = dir.y(), z = dir.z();
    const double el = std::atan2(z, std::hypot(x, y));
    const auto r =
        std::min(rows_ - 1, static_cast<std::size_t>(std::max(0.0, (el + kPi / 2.0) / d_)));
    const double u = (std::atan2(y, x) + kPi) / (2.0 * kPi);  // [0, 1]
    const auto k =
        std::min(counts_[r] - 1, static_cast<std::size_t>(u * static_cast<double>(counts_[r])));
    return first_[r] + k;
  }

 private:
  double d_;
  std::size_t rows_ = 0;
  std::vector<std::size_t> first_, counts_;
};

}  // namespace

LidarCoverage FramesToCover(const Lidar& lidar, double cell_rad, double fraction,
                            double horizon_s) {
  if (!(cell_rad > 0.0) || !std::isfinite(cell_rad))
    throw std::invalid_argument("FramesToCover: cell_rad must be > 0");
  if (!(fraction > 0.0 && fraction <= 1.0))
    throw std::invalid_argument("FramesToCover: fraction must be in (0, 1]");
  if (!(horizon_s > 0.0) || !std::isfinite(horizon_s))
    throw std::invalid_argument("FramesToCover: horizon_s must be > 0");
  LidarCoverage out;
  out.cell_rad = std::max(cell_rad, std::sqrt(4.0 * kPi / static_cast<double>(kMaxCoverageCells)));
  const DirectionCells cells(out.cell_rad);
  const double period_s = lidar.frame_period_s();
  const int horizon = std::max(1, static_cast<int>(std::ceil(horizon_s / period_s - 1e-9)));
  // The frame (1 = the last before t = 0) that first hit each cell; kNever:
  // none. Frames run in parallel; each cell keeps the smallest frame (an
  // atomic minimum), so the table does not depend on the order.
  constexpr std::uint16_t kNever = std::numeric_limits<std::uint16_t>::max();
  std::vector<std::atomic<std::uint16_t>> first(cells.size());
  for (auto& f : first) f.store(kNever, std::memory_order_relaxed);
  const int frames = std::min(horizon, static_cast<int>(kNever) - 1);
  tbb::parallel_for(1, frames + 1, [&](int k) {
    const auto frame = static_cast<std::uint16_t>(k);
    for (const LidarBeam& b : lidar.Beams(-k * period_s)) {
      std::atomic<std::uint16_t>& f = first[cells.Of(b.ray.direction)];
      std::uint16_t seen = f.load(std::memory_order_relaxed);
      while (frame < seen && !f.compare_exchange_weak(seen, frame, std::memory_order_relaxed)) {
      }
    }
  });
  std::vector<std::size_t> new_per_frame(static_cast<std::size_t>(frames) + 1, 0);
  for (const auto& f : first) {
    const std::uint16_t k = f.load(std::memory_order_relaxed);
    if (k != kNever) ++new_per_frame[k];
  }
  for (std::size_t n : new_per_frame) out.field_cells += n;
  const double wanted = fraction * static_cast<double>(out.field_cells);
  for (int k = 1; k <= frames; ++k) {
    out.covered_cells += new_per_frame[static_cast<std::size_t>(k)];
    out.frames = k;
    if (static_cast<double>(out.covered_cells) >= wanted - 1e-9) break;
  }
  return out;
}

}  // namespace uavsim::sensors
