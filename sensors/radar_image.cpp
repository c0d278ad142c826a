#include "sensors/radar_image.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

namespace uavsim::sensors {
namespace {

constexpr int kMinPlotPx = 512;
constexpr int kLeftPx = 64, kRightPx = 96, kTopPx = 28, kBottomPx = 46;
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kFontScale = 0.4;
const cv::Scalar kInk(0, 0, 0);

// A 1-2-5 step giving about `target` intervals over `span`.
double NiceStep(double span, int target) {
  const double raw = span / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * mag >= raw) return m * mag;
  return 10.0 * mag;
}

std::string Label(double v, double step) {
  char buf[32];
  // As many decimals as the step needs, and no "-0".
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  if (std::abs(v) < 1e-6 * step) v = 0.0;
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

void Text(cv::Mat& img, const std::string& s, cv::Point at, double align_x, double align_y) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(s, kFont, kFontScale, 1, &baseline);
  // align 0: text starts (or sits below) `at`; 1: ends at (or sits above) it.
  const cv::Point org(at.x - static_cast<int>(align_x * size.width),
                      at.y + static_cast<int>((1.0 - align_y) * size.height));
  cv::putText(img, s, org, kFont, kFontScale, kInk, 1, cv::LINE_AA);
}

}  // namespace

std::vector<std::uint8_t> EncodeRangeDopplerPng(const RangeDopplerMap& map,
                                                double dynamic_range_db) {
  const int nr = map.range_bins, nd = map.doppler_bins;
  if (nr <= 0 || nd <= 0 || map.power_db.size() != static_cast<std::size_t>(nr) * nd)
    throw std::invalid_argument("EncodeRangeDopplerPng: map of " + std::to_string(nr) + " x " +
                                std::to_string(nd) + " bins has " +
                                std::to_string(map.power_db.size()) + " values");
  if (!(dynamic_range_db > 0.0))
    throw std::invalid_argument("EncodeRangeDopplerPng: dynamic_range_db must be positive, got " +
                                std::to_string(dynamic_range_db));

  float top_db = -std::numeric_limits<float>::infinity();
  for (float v : map.power_db)
    if (std::isfinite(v)) top_db = std::max(top_db, v);
  if (!std::isfinite(top_db)) top_db = 0.0f;
  const double floor_db = top_db - dynamic_range_db;

  // One pixel per cell, row 0 = farthest range, then scaled up by blocks.
  cv::Mat grey(nr, nd, CV_8UC1);
  for (int r = 0; r < nr; ++r) {
    std::uint8_t* row = grey.ptr<std::uint8_t>(nr - 1 - r);
    for (int d = 0; d < nd; ++d) {
      const float v = map.power_db[static_cast<std::size_t>(d) * nr + r];
      const double t = std::isfinite(v) ? (v - floor_db) / dynamic_range_db : 0.0;
      row[d] = static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(t, 0.0, 1.0)));
    }
  }
  const int bx = std::max(1, (kMinPlotPx + nd - 1) / nd);
  const int by = std::max(1, (kMinPlotPx + nr - 1) / nr);
  const int w = nd * bx, h = nr * by;
  cv::Mat scaled, colour;
  cv::resize(grey, scaled, cv::Size(w, h), 0, 0, cv::INTER_NEAREST);
  cv::applyColorMap(scaled, colour, cv::COLORMAP_VIRIDIS);

  cv::Mat img(kTopPx + h + kBottomPx, kLeftPx + w + kRightPx, CV_8UC3, cv::Scalar(255, 255, 255));
  colour.copyTo(img(cv::Rect(kLeftPx, kTopPx, w, h)));
  cv::rectangle(img, cv::Rect(kLeftPx - 1, kTopPx - 1, w + 2, h + 2), kInk, 1);

  // Axes in metres and m/s when the bin sizes are known, else in bins.
  const bool metric = map.range_bin_m > 0.0 && map.velocity_bin_mps > 0.0;
  const double dr = metric ? map.range_bin_m : 1.0;
  const double dv = metric ? map.velocity_bin_mps : 1.0;
  const double range_max = nr * dr;
  const double r_step = NiceStep(range_max, 8);
  for (double x = 0.0; x <= range_max + 1e-9; x += r_step) {
    // Cell r covers [r dr, (r + 1) dr) drawn at rows counted from the bottom.
    const int y = kTopPx + h - static_cast<int>(std::lround(x / dr * by));
    cv::line(img, {kLeftPx - 5, y}, {kLeftPx - 1, y}, kInk, 1);
    Text(img, Label(x, r_step), {kLeftPx - 8, y}, 1.0, 0.5);
  }
  const double half = nd / 2;  // the zero-velocity column (fftshift)
  const double v_lo = -half * dv, v_hi = (nd - half) * dv;
  const double v_step = NiceStep(v_hi - v_lo, 6);
  for (double v = std::ceil(v_lo / v_step) * v_step; v <= v_hi + 1e-9; v += v_step) {
    // Velocity v is at the centre of its cell: column (v / dv + half + 0.5).
    const int x = kLeftPx + static_cast<int>(std::lround((v / dv + half + 0.5) * bx));
    if (x < kLeftPx || x > kLeftPx + w) continue;
    cv::line(img, {x, kTopPx + h}, {x, kTopPx + h + 4}, kInk, 1);
    Text(img, Label(v, v_step), {x, kTopPx + h + 7}, 0.5, 0.0);
  }
  Text(img, metric ? "radial velocity (m/s), receding > 0" : "Doppler bin",
       {kLeftPx + w / 2, kTopPx + h + 26}, 0.5, 0.0);
  Text(img, metric ? "range (m)" : "range bin", {4, 8}, 0.0, 0.0);
  Text(img, "dB", {kLeftPx + w + 12, 8}, 0.0, 0.0);

  // Colour bar: the top of the scale at the top.
  const int bar_x = kLeftPx + w + 12, bar_w = 14;
  cv::Mat ramp(h, 1, CV_8UC1);
  for (int y = 0; y < h; ++y)
    ramp.at<std::uint8_t>(y) =
        static_cast<std::uint8_t>(std::lround(255.0 * (h - 1 - y) / std::max(1, h - 1)));
  cv::Mat ramp_colour, ramp_wide;
  cv::applyColorMap(ramp, ramp_colour, cv::COLORMAP_VIRIDIS);
  cv::resize(ramp_colour, ramp_wide, cv::Size(bar_w, h), 0, 0, cv::INTER_NEAREST);
  ramp_wide.copyTo(img(cv::Rect(bar_x, kTopPx, bar_w, h)));
  cv::rectangle(img, cv::Rect(bar_x - 1, kTopPx - 1, bar_w + 2, h + 2), kInk, 1);
  // Ticks at round dB values (multiples of the step) within the scale.
  const double db_step = NiceStep(dynamic_range_db, 6);
  for (double db = std::ceil(floor_db / db_step) * db_step; db <= top_db + 1e-9; db += db_step) {
    const double t = (top_db - db) / dynamic_range_db;  // 0 at the top
    const int y = kTopPx + static_cast<int>(std::lround(t * (h - 1)));
    cv::line(img, {bar_x + bar_w, y}, {bar_x + bar_w + 3, y}, kInk, 1);
    Text(img, Label(db, db_step), {bar_x + bar_w + 6, y}, 0.0, 0.5);
  }

  std::vector<std::uint8_t> png;
  if (!cv::imencode(".png", img, png, {cv::IMWRITE_PNG_COMPRESSION, 1}))
    throw std::runtime_error("EncodeRangeDopplerPng: OpenCV could not encode the image");
  return png;
}

}  // namespace uavsim::sensors
