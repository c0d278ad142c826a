// Radar processing against theory (issue 4, item 6). Cubes are built here
// from fmcw_radar.h's closed-form signal model, independently of the
// synthesis; the end-to-end cases at the bottom go through FmcwRadar. Checked:
// the windows' coherent and processing gains, range and velocity within
// Delta R = c / (2 B_s) and Delta v = lambda / (2 N_c T_c), two-target range
// resolution, MUSIC and ESPRIT at the Cramer-Rao bound and below the FFT
// beamscan, clutter removal, CA-CFAR's false-alarm rate against its design
// Pfa (binomial interval), world-frame points, MDL, the range-Doppler PNG,
// and through the synthesis the 40 log10 R fall of the detection SNR.
#include "sensors/radar_processor.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <complex>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"
#include "core/interrupt.h"
#include "core/json_io.h"
#include "core/pose.h"
#include "core/rng.h"
#include "core/world_geometry.h"
#include "sensors/fmcw_radar.h"
#include "sensors/radar_image.h"

using uavsim::core::RngStream;
using uavsim::sensors::AngleMethod;
using uavsim::sensors::AngleOfArrival;
using uavsim::sensors::FmcwRadar;
using uavsim::sensors::FmcwRadarConfig;
using uavsim::sensors::RadarCube;
using uavsim::sensors::RadarDetection;
using uavsim::sensors::RadarFrame;
using uavsim::sensors::RadarProcessingConfig;
using uavsim::sensors::RadarProcessor;
using uavsim::sensors::RadarWindow;
using uavsim::sensors::RangeDopplerCube;
using uavsim::sensors::SourceCount;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kC = 299792458.0;
constexpr double kDeg = kPi / 180.0;

// A point target in the radar frame: range at the frame's start, radial
// velocity (receding > 0), direction, and |a|^2 = SNR per ADC sample.
struct Target {
  double range_m;
  double velocity_mps;
  double az_deg;
  double el_deg;
  double snr_db;
};

struct Waveform {
  double lambda_m, slope_hz_per_s, fs_hz, chirp_period_s, dx_m, dy_m;
  double range_bin_m;       // c / (2 B_s), B_s = K Ns / fs: the sampled sweep
  double velocity_bin_mps;  // lambda / (2 Nc T_c)
};

Waveform WaveformOf(const FmcwRadarConfig& c) {
  Waveform w;
  w.lambda_m = kC / (c.carrier_ghz * 1e9);
  w.slope_hz_per_s = c.bandwidth_mhz * 1e6 / (c.chirp_duration_us * 1e-6);
  w.fs_hz = c.sample_rate_msps * 1e6;
  w.chirp_period_s = (c.chirp_duration_us + c.idle_time_us) * 1e-6;
  w.dx_m = c.spacing_x_wavelengths * w.lambda_m;
  w.dy_m = c.spacing_y_wavelengths * w.lambda_m;
  w.range_bin_m = kC / (2.0 * w.slope_hz_per_s * c.adc_samples / w.fs_hz);
  w.velocity_bin_mps = w.lambda_m / (2.0 * c.chirps_per_frame * w.chirp_period_s);
  return w;
}

// fmcw_radar.h's model, sample by sample:
//   a exp(j [2 pi f_b s / fs + 4 pi R / lambda + 2 pi (2 v / lambda) c T_c
//            + 2 pi (ix dx u_y + iy dy u_z) / lambda]),  f_b = 2 K R / c,
// plus complex Gaussian noise of unit power per sample if `noise` is given.
RadarCube ClosedFormCube(const FmcwRadarConfig& c, const std::vector<Target>& targets,
                         RngStream* noise) {
  const Waveform w = WaveformOf(c);
  RadarCube cube;
  cube.Resize(c.adc_samples, c.chirps_per_frame, c.nx, c.ny);
  std::vector<std::complex<double>> sum(cube.data.size());
  for (const Target& t : targets) {
    const double u_y = std::cos(t.el_deg * kDeg) * std::sin(t.az_deg * kDeg);
    const double u_z = std::sin(t.el_deg * kDeg);
    const double f_b = 2.0 * w.slope_hz_per_s * t.range_m / kC;
    const double a = std::sqrt(std::pow(10.0, t.snr_db / 10.0));
    for (int iy = 0; iy < c.ny; ++iy)
      for (int ix = 0; ix < c.nx; ++ix)
        for (int ch = 0; ch < c.chirps_per_frame; ++ch) {
          const double phase0 =
              4.0 * kPi * t.range_m / w.lambda_m +
              2.0 * kPi * (2.0 * t.velocity_mps / w.lambda_m) * ch * w.chirp_period_s +
              2.0 * kPi * (ix * w.dx_m * u_y + iy * w.dy_m * u_z) / w.lambda_m;
          const std::size_t base = cube.Index(0, ch, ix, iy);
          for (int s = 0; s < c.adc_samples; ++s)
            sum[base + s] += std::polar(a, phase0 + 2.0 * kPi * f_b * s / w.fs_hz);
        }
  }
  for (std::size_t i = 0; i < sum.size(); ++i) {
    std::complex<double> v = sum[i];
    if (noise) v += std::complex<double>(noise->Normal(), noise->Normal()) * std::sqrt(0.5);
    cube.data[i] = std::complex<float>(v);
  }
  return cube;
}

Eigen::Vector3d Direction(double az_rad, double el_rad) {
  return {std::cos(el_rad) * std::cos(az_rad), std::cos(el_rad) * std::sin(az_rad),
          std::sin(el_rad)};
}
Eigen::Vector3d Direction(const AngleOfArrival& a) {
  return Direction(a.azimuth_rad, a.elevation_rad);
}
double AngleBetweenRad(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Detections within `range_tol_m` of a range and `velocity_tol_mps` of a velocity.
int CountNear(const std::vector<RadarDetection>& dets, double lo_m, double hi_m,
              double velocity_mps, double velocity_tol_mps) {
  return static_cast<int>(std::count_if(dets.begin(), dets.end(), [&](const RadarDetection& d) {
    return d.range_m >= lo_m && d.range_m <= hi_m &&
           std::abs(d.radial_velocity_mps - velocity_mps) <= velocity_tol_mps;
  }));
}

// A radial velocity away from the clutter notch (|v| >= 1.5 m/s, four
// Doppler bins), of either sign, up to 11 m/s (the unambiguous limit is 12.2).
double MovingVelocity(RngStream& rng) {
  const double v = rng.Uniform(1.5, 11.0);
  return rng.Bernoulli(0.5) ? v : -v;
}

std::string ConfigErrorOf(const uavsim::core::Json& j) {
  RadarProcessingConfig c;
  try {
    uavsim::core::FromJson(j, "r.json", "/nodes/2/sensor/processing", c);
  } catch (const uavsim::core::ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("RadarProcessingConfig: defaults round-trip, rules give clear errors", "[sensors]") {
  using uavsim::core::Json;
  const Json written = uavsim::core::ToJson(RadarProcessingConfig{});
  CHECK(written.at("angle_method") == "music");
  CHECK(written.at("range_window") == "hann");
  CHECK(written.at("cfar_pfa") == 1e-5);
  CHECK(ConfigErrorOf(written).empty());
  CHECK(ConfigErrorOf(Json{{"cfar_pfa", 0.5}}) ==
        "r.json: /nodes/2/sensor/processing/cfar_pfa: expected a number in [1e-12, 0.1], got 0.5");
  CHECK_THAT(
      ConfigErrorOf(Json{{"range_window", "hanning"}}),
      Catch::Contains("expected one of \"hann\", \"hamming\", \"blackman\", \"rectangular\""));
  CHECK_THAT(ConfigErrorOf(Json{{"cfar_guard_cells", 2}}), Catch::Contains("cfar_guard_"));
  CHECK_THAT(ConfigErrorOf(Json{{"source_count", "two"}}),
             Catch::Contains("expected one of \"one\", \"mdl\""));

  // Rules that need the waveform are the processor's.
  FmcwRadarConfig c;
  c.chirps_per_frame = 8;  // Doppler window 2 * (2 + 4) + 1 = 13 > 8
  try {
    RadarProcessor p(c);
    FAIL("expected std::invalid_argument");
  } catch (const std::invalid_argument& e) {
    CHECK_THAT(e.what(), Catch::StartsWith("processing/cfar_training_doppler_cells: the CFAR "
                                           "window (2 * (guard + training) + 1 = 13 Doppler "
                                           "cells) exceeds chirps_per_frame (8)"));
  }
  FmcwRadarConfig m;
  m.processing.source_count = SourceCount::kMdl;
  m.processing.max_sources = 4;
  m.nx = 2;
  m.ny = 2;
  CHECK_THROWS_WITH(RadarProcessor(m), Catch::StartsWith("processing/max_sources: 4 sources"));
  RadarProcessor p(FmcwRadarConfig{});
  RadarCube wrong;
  wrong.Resize(256, 64, 4, 3);
  CHECK_THROWS_WITH(p.Process(wrong, Eigen::Isometry3d::Identity(), 0.0),
                    Catch::Contains("does not match the config's 512 x 64 x 4 x 3"));
}

TEST_CASE("RadarProcessor: windows and the CA-CFAR threshold reduce to the classical forms",
          "[sensors]") {
  // DFT-even Hann: 0.5 - 0.5 cos(2 pi n / N); sum N / 2, sum of squares 3N / 8.
  const std::vector<double> hann = RadarProcessor::Window(RadarWindow::kHann, 64);
  CHECK(hann[0] == 0.0);
  CHECK(hann[32] == Approx(1.0));
  CHECK(hann[16] == Approx(0.5));
  double s1 = 0.0, s2 = 0.0;
  for (double x : hann) s1 += x, s2 += x * x;
  CHECK(s1 == Approx(32.0));
  CHECK(s2 == Approx(24.0));
  CHECK(RadarProcessor::Window(RadarWindow::kBlackman, 8)[0] == Approx(0.0).margin(1e-12));
  CHECK(RadarProcessor::Window(RadarWindow::kHamming, 8)[0] == Approx(0.08));

  // One look (M = 1), independent cells: Pfa = (1 + alpha / N)^-N, so
  // alpha = N (Pfa^(-1/N) - 1) (Richards, Fundamentals of Radar Signal
  // Processing, eq. 6.19).
  for (int n : {8, 24, 248})
    for (double pfa : {1e-3, 1e-6}) {
      const double classical = n * (std::pow(pfa, -1.0 / n) - 1.0);
      CHECK(RadarProcessor::CaCfarThresholdFactor(pfa, n, n, 1.0, 1) ==
            Approx(classical).epsilon(1e-9));
      CHECK(RadarProcessor::CaCfarPfa(classical, n, n, 1.0, 1) == Approx(pfa).epsilon(1e-9));
    }
  // M looks: Pfa = sum_{k<M} C(NM + k - 1, k) beta^k / (1 + beta)^(NM + k),
  // written out for M = 2, N = 10 (NM = 20), beta = alpha / N.
  const double alpha = 3.0, beta = alpha / 10.0;
  const double two_looks = std::pow(1.0 + beta, -20.0) + 20.0 * beta * std::pow(1.0 + beta, -21.0);
  CHECK(RadarProcessor::CaCfarPfa(alpha, 10, 20.0, 1.0, 2) == Approx(two_looks).epsilon(1e-12));

  // Rectangular windows make DFT cells independent: the training sum is
  // then Gamma(N M, 1) exactly.
  FmcwRadarConfig c;
  c.processing.range_window = c.processing.doppler_window = RadarWindow::kRectangular;
  const RadarProcessor rect(c);
  const int n = (2 * 10 + 1) * (2 * 6 + 1) - 5 * 5;
  CHECK(rect.cfar_training_cells() == n);
  CHECK(rect.cfar_training_shape() == Approx(n * 12.0));
  CHECK(rect.cfar_training_scale() == Approx(1.0));
  // Hann correlates neighbouring cells: fewer effective training cells.
  const RadarProcessor hann_p{FmcwRadarConfig{}};
  CHECK(hann_p.cfar_training_shape() < 0.5 * n * 12.0);
  CHECK(hann_p.cfar_threshold_factor() > rect.cfar_threshold_factor());
}

TEST_CASE("RadarProcessor: a tone's range profile peaks at its beat bin with the window's gain",
          "[sensors]") {
  const FmcwRadarConfig c;
  const Waveform w = WaveformOf(c);
  const RadarProcessor p(c);
  CHECK(p.range_bin_m() == Approx(w.range_bin_m));
  CHECK(p.range_bin_m() == Approx(0.1952).epsilon(1e-3));
  CHECK(p.velocity_bin_mps() == Approx(w.velocity_bin_mps));
  // A target on bin 150: f_b = 150 fs / Ns.
  const RadarCube cube = ClosedFormCube(c, {{150 * w.range_bin_m, 0.0, 0.0, 0.0, 0.0}}, nullptr);
  const RadarCube profiles = p.RangeProfiles(cube);
  for (int ch : {0, 17, 63}) {
    int best = 0;
    for (int k = 0; k < c.adc_samples; ++k)
      if (std::abs(profiles.at(k, ch, 1, 2)) > std::abs(profiles.at(best, ch, 1, 2))) best = k;
    CHECK(best == 150);
    // Coherent gain of Hann: |sum w| = Ns / 2 for unit amplitude.
    CHECK(std::abs(profiles.at(150, ch, 1, 2)) == Approx(c.adc_samples / 2.0).epsilon(1e-4));
    // Hann's spectrum is exactly three bins wide for an on-bin tone.
    CHECK(std::abs(profiles.at(149, ch, 1, 2)) == Approx(c.adc_samples / 4.0).epsilon(1e-4));
    CHECK(std::abs(profiles.at(147, ch, 1, 2)) < 1e-3 * c.adc_samples);
  }
}

TEST_CASE("RadarProcessor: the range-Doppler peak has the windows' processing gain and sign",
          "[sensors]") {
  const FmcwRadarConfig c;
  const Waveform w = WaveformOf(c);
  const RadarProcessor p(c);
  // On-bin range (bin 200) and velocity (+5 bins: receding), SNR 1 per
  // sample, no noise. Noise-normalised peak = (sum w_r)^2 / sum w_r^2 *
  // (sum w_d)^2 / sum w_d^2 = (512 / 1.5) (64 / 1.5): Ns Nc less Hann's
  // 1.76 dB per FFT. Summing the M antennas' powers raises signal and noise
  // alike (it narrows the noise's spread, which CFAR's threshold uses).
  for (int m : {5, -7}) {
    const RadarCube cube = ClosedFormCube(
        c, {{200 * w.range_bin_m, m * w.velocity_bin_mps, 20.0, -10.0, 0.0}}, nullptr);
    const RangeDopplerCube rd = p.Transform(cube);
    const int d = c.chirps_per_frame / 2 + m;
    const double expected = (512.0 / 1.5) * (64.0 / 1.5);
    CHECK(10.0 * std::log10(rd.power_at(200, d)) ==
          Approx(10.0 * std::log10(expected)).margin(0.01));
    const std::vector<RadarDetection> dets = p.Detect(rd);
    REQUIRE(!dets.empty());
    CHECK(dets[0].range_bin == 200);
    CHECK(dets[0].doppler_bin == d);
    CHECK(dets[0].radial_velocity_mps == Approx(m * w.velocity_bin_mps).margin(1e-6));
  }
}

TEST_CASE("RadarProcessor: a point target is recovered within the theoretical resolutions",
          "[sensors]") {
  const FmcwRadarConfig c;
  const Waveform w = WaveformOf(c);
  // Delta R = c / (2 B_s) = 0.195 m, Delta v = lambda / (2 Nc T_c) = 0.380 m/s;
  // angle: the aperture's null-to-null half width 2 / N in direction cosine.
  CHECK(w.range_bin_m == Approx(0.1952).epsilon(1e-3));
  CHECK(w.velocity_bin_mps == Approx(0.3802).epsilon(1e-3));
  for (AngleMethod method : {AngleMethod::kMusic, AngleMethod::kEsprit, AngleMethod::kBeamscan}) {
    FmcwRadarConfig cm = c;
    cm.processing.angle_method = method;
    const RadarProcessor p(cm);
    RngStream rng(11, "single-target");
    for (int trial = 0; trial < 6; ++trial) {
      const Target t{rng.Uniform(5.0, 90.0), MovingVelocity(rng), rng.Uniform(-50.0, 50.0),
                     rng.Uniform(-25.0, 25.0), -15.0};
      INFO("method " << static_cast<int>(method) << " target R " << t.range_m << " v "
                     << t.velocity_mps << " az " << t.az_deg << " el " << t.el_deg);
      const RadarFrame f =
          p.Process(ClosedFormCube(cm, {t}, &rng), Eigen::Isometry3d::Identity(), 0.0);
      REQUIRE(!f.points.empty());
      const auto& pt = f.points[0];  // strongest first
      const Eigen::Vector3d p_R(pt.x_m, pt.y_m, pt.z_m);
      CHECK(std::abs(p_R.norm() - t.range_m) < w.range_bin_m);
      CHECK(std::abs(pt.radial_velocity_mps - t.velocity_mps) < w.velocity_bin_mps);
      // Interpolation does much better than the resolution.
      CHECK(std::abs(p_R.norm() - t.range_m) < 0.25 * w.range_bin_m);
      CHECK(std::abs(pt.radial_velocity_mps - t.velocity_mps) < 0.25 * w.velocity_bin_mps);
      const Eigen::Vector3d u = p_R.normalized();
      const Eigen::Vector3d truth = Direction(t.az_deg * kDeg, t.el_deg * kDeg);
      CHECK(std::abs(u.y() - truth.y()) < 2.0 / c.nx);
      CHECK(std::abs(u.z() - truth.z()) < 2.0 / c.ny);
      CHECK(AngleBetweenRad(u, truth) < 3.0 * kDeg);
      // Integrated SNR: -15 dB per sample + 10 log10(512 x 64) - 2 x 1.76 dB
      // of Hann = 26.6 dB, less up to 2 x 1.42 dB of scalloping off-bin.
      CHECK(pt.snr_db > 26.6 - 2.9 - 1.0);
      CHECK(pt.snr_db < 26.6 + 1.0);
    }
  }
}

TEST_CASE("RadarProcessor: two targets 0.5 Delta R apart merge, 2 Delta R apart separate",
          "[sensors]") {
  // Two equal targets at one velocity and angle. The two-point criterion
  // is for echoes that add in power, i.e. in phase quadrature at the peak:
  // there their spectra add exactly as powers. Their relative phase is set
  // by moving the second by less than lambda / 2 (under 2 mm): the phase of
  // target i at range bin k is 4 pi R_i / lambda + pi (f_i - k) for the
  // DFT-even window, so quadrature needs 4 pi dR / lambda + pi dR / Delta R
  // = pi / 2 (mod 2 pi). Coherent in-phase echoes are harder to split
  // (Hann's mainlobe is 2 Delta R to its first null): they separate from
  // 3 Delta R, and merge at 2.
  const FmcwRadarConfig c;
  const Waveform w = WaveformOf(c);
  const RadarProcessor p(c);
  const double dr = w.range_bin_m;
  const auto with_phase = [&](double separation_m, double relative_rad) {
    const double k = 4.0 * kPi / w.lambda_m + kPi / dr;
    const double now = std::fmod(k * separation_m, 2.0 * kPi);
    const double shift = std::fmod(relative_rad - now + 4.0 * kPi, 2.0 * kPi) / k;
    return separation_m + shift;
  };
  const auto detections = [&](double separation_dr, double relative_rad, RngStream& rng) {
    const double r1 = rng.Uniform(20.0, 60.0);
    const double r2 = r1 + with_phase(separation_dr * dr, relative_rad);
    const RadarCube cube =
        ClosedFormCube(c, {{r1, 3.0, 10.0, 5.0, -15.0}, {r2, 3.0, 10.0, 5.0, -15.0}}, &rng);
    return CountNear(p.Detect(p.Transform(cube)), r1 - 1.0, r2 + 1.0, 3.0, 1.0);
  };
  RngStream rng(12, "two-targets");
  for (int trial = 0; trial < 12; ++trial) {
    INFO("trial " << trial);
    CHECK(detections(0.5, 0.5 * kPi, rng) == 1);
    CHECK(detections(2.0, 0.5 * kPi, rng) == 2);
    CHECK(detections(2.0, 0.0, rng) == 1);
    CHECK(detections(3.0, 0.0, rng) == 2);
  }
}

TEST_CASE("RadarProcessor: at high SNR MUSIC's angle error is below the FFT beamscan's",
          "[sensors]") {
  const FmcwRadarConfig c;
  const RadarProcessor p(c);
  RngStream rng(13, "angles");
  double music2 = 0.0, esprit2 = 0.0, beam2 = 0.0;
  const int n = 60;
  for (int i = 0; i < n; ++i) {
    const Target t{rng.Uniform(10.0, 80.0), MovingVelocity(rng), rng.Uniform(-50.0, 50.0),
                   rng.Uniform(-25.0, 25.0), 0.0};
    const RangeDopplerCube rd = p.Transform(ClosedFormCube(c, {t}, &rng));
    const std::vector<RadarDetection> dets = p.Detect(rd);
    REQUIRE(!dets.empty());
    const Eigen::MatrixXcd x = p.Snapshots(rd, dets[0]);
    const Eigen::Vector3d truth = Direction(t.az_deg * kDeg, t.el_deg * kDeg);
    const auto music = p.Music(x, 1);
    const auto esprit = p.Esprit(x, 1);
    REQUIRE(music.size() == 1);
    REQUIRE(esprit.size() == 1);
    music2 += std::pow(AngleBetweenRad(Direction(music[0]), truth), 2);
    esprit2 += std::pow(AngleBetweenRad(Direction(esprit[0]), truth), 2);
    beam2 += std::pow(AngleBetweenRad(Direction(p.Beamscan(x.col(0))), truth), 2);
  }
  const double music_deg = std::sqrt(music2 / n) / kDeg, esprit_deg = std::sqrt(esprit2 / n) / kDeg,
               beam_deg = std::sqrt(beam2 / n) / kDeg;
  INFO("RMS error: MUSIC " << music_deg << " deg, ESPRIT " << esprit_deg << " deg, beamscan "
                           << beam_deg << " deg");
  // The 64-point beamscan's grid step is 2/64 in direction cosine (1.8 deg
  // at broadside); its error is the grid's, the subspace methods' the noise's.
  CHECK(music_deg < 0.5 * beam_deg);
  CHECK(esprit_deg < 0.5 * beam_deg);
  CHECK(music_deg < 0.3);
  CHECK(beam_deg > 0.3);
}

TEST_CASE("RadarProcessor: MUSIC and ESPRIT on one snapshot reach the Cramer-Rao bound",
          "[sensors]") {
  // One source, one snapshot x = s a(psi) + n, unit noise: for the
  // spatial frequency psi_x = 2 pi dx u_y / lambda (radians per element),
  // CRB = 1 / (2 SNR sum_m (ix_m - mean ix)^2) = 6 / (SNR ny nx (nx^2 - 1))
  // (Stoica & Nehorai, IEEE TASSP 37(5), 1989; psi_x and psi_y decouple on a
  // full rectangular grid).
  const FmcwRadarConfig c;
  const RadarProcessor p(c);
  const double snr = 1000.0;  // 30 dB per element
  const double crb = 6.0 / (snr * c.ny * c.nx * (c.nx * c.nx - 1));
  RngStream rng(14, "crb");
  double music2 = 0.0, esprit2 = 0.0, beam2 = 0.0;
  const int n = 400;
  const auto psi = [&](const AngleOfArrival& a) {
    return 2.0 * kPi * c.spacing_x_wavelengths * std::cos(a.elevation_rad) *
           std::sin(a.azimuth_rad);
  };
  for (int i = 0; i < n; ++i) {
    const AngleOfArrival truth{rng.Uniform(-40.0, 40.0) * kDeg, rng.Uniform(-20.0, 20.0) * kDeg};
    // The steering vector from the header's geometry, written out here.
    Eigen::VectorXcd x(c.nx * c.ny);
    const double u_y = std::cos(truth.elevation_rad) * std::sin(truth.azimuth_rad);
    const double u_z = std::sin(truth.elevation_rad);
    const std::complex<double> s = std::polar(std::sqrt(snr), rng.Uniform(0.0, 2.0 * kPi));
    for (int iy = 0; iy < c.ny; ++iy)
      for (int ix = 0; ix < c.nx; ++ix)
        x(iy * c.nx + ix) = s * std::polar(1.0, 2.0 * kPi *
                                                    (ix * c.spacing_x_wavelengths * u_y +
                                                     iy * c.spacing_y_wavelengths * u_z)) +
                            std::complex<double>(rng.Normal(), rng.Normal()) * std::sqrt(0.5);
    CHECK((p.Steering(truth) - x / s).norm() < 1.0);  // the same geometry
    const Eigen::MatrixXcd snapshots = x;
    music2 += std::pow(psi(p.Music(snapshots, 1).at(0)) - psi(truth), 2);
    esprit2 += std::pow(psi(p.Esprit(snapshots, 1).at(0)) - psi(truth), 2);
    beam2 += std::pow(psi(p.Beamscan(x)) - psi(truth), 2);
  }
  const double bound = std::sqrt(crb);
  INFO("RMS psi error: MUSIC " << std::sqrt(music2 / n) << ", ESPRIT " << std::sqrt(esprit2 / n)
                               << ", beamscan " << std::sqrt(beam2 / n) << "; sqrt(CRB) " << bound);
  CHECK(std::sqrt(music2 / n) < 1.2 * bound);
  CHECK(std::sqrt(esprit2 / n) < 1.25 * bound);
  CHECK(std::sqrt(music2 / n) > 0.85 * bound);  // no estimator beats the bound
  CHECK(std::sqrt(beam2 / n) > 3.0 * bound);    // grid-limited
}

TEST_CASE("RadarProcessor: MDL counts two well-separated scatterers in one cell", "[sensors]") {
  FmcwRadarConfig c;
  c.processing.source_count = SourceCount::kMdl;
  const RadarProcessor p(c);
  RngStream rng(15, "mdl");
  for (int trial = 0; trial < 5; ++trial) {
    const double r = rng.Uniform(20.0, 60.0);
    // Within one range cell, at one velocity, 65 deg apart in azimuth.
    const RadarCube two = ClosedFormCube(
        c, {{r, 3.0, -35.0, 0.0, -5.0}, {r + 0.3 * p.range_bin_m(), 3.0, 30.0, 10.0, -5.0}}, &rng);
    const RangeDopplerCube rd = p.Transform(two);
    const std::vector<RadarDetection> dets = p.Detect(rd);
    REQUIRE(!dets.empty());
    const Eigen::MatrixXcd x = p.Snapshots(rd, dets[0]);
    REQUIRE(p.SourceCountOf(x) == 2);
    for (const auto& found : {p.Music(x, 2), p.Esprit(x, 2)}) {
      REQUIRE(found.size() == 2);
      const Eigen::Vector3d a = Direction(-35.0 * kDeg, 0.0),
                            b = Direction(30.0 * kDeg, 10.0 * kDeg);
      const double err_ab = std::max(AngleBetweenRad(Direction(found[0]), a),
                                     AngleBetweenRad(Direction(found[1]), b));
      const double err_ba = std::max(AngleBetweenRad(Direction(found[0]), b),
                                     AngleBetweenRad(Direction(found[1]), a));
      CHECK(std::min(err_ab, err_ba) < 1.0 * kDeg);
    }
    // And one target is one source.
    const RangeDopplerCube one = p.Transform(ClosedFormCube(c, {{r, 3.0, 20.0, 5.0, -5.0}}, &rng));
    CHECK(p.SourceCountOf(p.Snapshots(one, p.Detect(one).at(0))) == 1);
  }
}

TEST_CASE("RadarProcessor: a static wall disappears after clutter removal, a mover stays",
          "[sensors]") {
  // A wall at x = 40 m as 41 strong static scatterers (+10 dB per sample),
  // and a weak target (-15 dB) at 25 m receding at 4 m/s.
  std::vector<Target> scene;
  for (int i = -20; i <= 20; ++i) {
    const double y = 0.5 * i;
    scene.push_back({std::hypot(40.0, y), 0.0, std::atan2(y, 40.0) / kDeg, 0.0, 10.0});
  }
  scene.push_back({25.0, 4.0, 5.0, 0.0, -15.0});
  for (bool removal : {false, true}) {
    FmcwRadarConfig c;
    c.processing.clutter_removal = removal;
    const RadarProcessor p(c);
    RngStream rng(16, "wall");
    const std::vector<RadarDetection> dets = p.Detect(p.Transform(ClosedFormCube(c, scene, &rng)));
    const double dv = p.velocity_bin_mps();
    INFO("clutter removal " << removal << ", " << dets.size() << " detections");
    CHECK(CountNear(dets, 24.5, 25.5, 4.0, dv) == 1);
    const int wall = CountNear(dets, 39.0, 42.0, 0.0, 1.5 * dv);
    if (removal) {
      CHECK(wall == 0);
      // Nothing else is left: the wall's energy is gone, not spread.
      CHECK(dets.size() <= 2);
    } else {
      CHECK(wall >= 1);
    }
  }
}

TEST_CASE("RadarProcessor: CFAR's false-alarm rate on noise is its design Pfa", "[sensors]") {
  // Noise-only cubes; every tested cell is a Bernoulli(Pfa) trial. The
  // decisions of neighbouring cells share training cells, so the count's
  // spread is somewhat above the binomial; 4 binomial sigmas hold it.
  struct Case {
    const char* name;
    RadarWindow window;
    int nx, ny;
    bool clutter_removal;
  };
  for (const Case& k : {Case{"Hann, 12 antennas, clutter removal", RadarWindow::kHann, 4, 3, true},
                        Case{"Hann, 12 antennas", RadarWindow::kHann, 4, 3, false},
                        Case{"rectangular, 1 antenna", RadarWindow::kRectangular, 1, 1, false}}) {
    FmcwRadarConfig c;
    c.nx = k.nx;
    c.ny = k.ny;
    c.processing.range_window = c.processing.doppler_window = k.window;
    c.processing.clutter_removal = k.clutter_removal;
    c.processing.cfar_pfa = 1e-3;
    const RadarProcessor p(c);
    RngStream rng(17, k.name);
    double detected = 0.0, tested = 0.0;
    for (int frame = 0; frame < 16; ++frame) {
      const auto cfar = p.Cfar(p.Transform(ClosedFormCube(c, {}, &rng)).power);
      for (std::uint8_t d : cfar.detected) detected += d;
      tested += static_cast<double>(cfar.cells_tested);
    }
    const double expected = tested * 1e-3, sigma = std::sqrt(tested * 1e-3 * (1.0 - 1e-3));
    INFO(k.name << ": " << detected << " false alarms in " << tested << " cells, expected "
                << expected << " +- " << sigma);
    CHECK(std::abs(detected - expected) < 4.0 * sigma);
  }
}

TEST_CASE("RadarProcessor: a noise-free cube gives its targets, not its rounding errors",
          "[sensors]") {
  // Without thermal noise the CFAR estimate is floored at a tenth of the
  // thermal level, so weak and strong targets alike give one detection.
  const FmcwRadarConfig c;
  const RadarProcessor p(c);
  RngStream rng(24, "noise-free");
  for (double snr_db : {-30.0, 0.0, 20.0}) {
    const Target t{rng.Uniform(10.0, 90.0), MovingVelocity(rng), rng.Uniform(-40.0, 40.0), 0.0,
                   snr_db};
    const std::vector<RadarDetection> dets = p.Detect(p.Transform(ClosedFormCube(c, {t}, nullptr)));
    INFO("SNR " << snr_db << " dB per sample");
    REQUIRE(dets.size() == 1);
    CHECK(std::abs(dets[0].range_m - t.range_m) < 0.25 * p.range_bin_m());
  }
}

TEST_CASE("RadarProcessor: points are in the world frame of a rotated, translated radar",
          "[sensors]") {
  FmcwRadarConfig c;
  c.pose.position_m = {10.0, -5.0, 3.0};
  c.pose.rpy_deg = {5.0, -20.0, 30.0};
  const Eigen::Isometry3d X_WR = c.pose.ToIsometry();
  const RadarProcessor p(c);
  RngStream rng(18, "world");
  for (const Eigen::Vector3d& p_W :
       {Eigen::Vector3d(40.0, 10.0, 12.0), Eigen::Vector3d(25.0, -18.0, 8.0)}) {
    // Where the target is seen from the radar, by hand.
    const Eigen::Vector3d p_R = X_WR.inverse() * p_W;
    const double range = p_R.norm();
    const double az = std::atan2(p_R.y(), p_R.x()), el = std::asin(p_R.z() / range);
    const RadarCube cube = ClosedFormCube(c, {{range, -2.5, az / kDeg, el / kDeg, 0.0}}, &rng);
    const RadarFrame f = p.Process(cube, X_WR, 1.25);
    CHECK(f.t_capture_s == 1.25);
    REQUIRE(!f.points.empty());
    const Eigen::Vector3d got(f.points[0].x_m, f.points[0].y_m, f.points[0].z_m);
    INFO("expected " << p_W.transpose() << ", got " << got.transpose());
    CHECK((got - p_W).norm() < 0.15);
    CHECK(f.points[0].radial_velocity_mps == Approx(-2.5).margin(0.1));
    // The identity pose gives the radar-frame point.
    const RadarFrame fr = p.Process(cube, Eigen::Isometry3d::Identity(), 1.25);
    CHECK((Eigen::Vector3d(fr.points[0].x_m, fr.points[0].y_m, fr.points[0].z_m) - p_R).norm() <
          0.15);
  }
}

TEST_CASE("RadarProcessor: a frame reports its bytes and a noise-normalised map", "[sensors]") {
  const FmcwRadarConfig c;
  const RadarProcessor p(c);
  RngStream rng(19, "frame");
  const RadarCube cube = ClosedFormCube(c, {{30.0, 5.0, 0.0, 0.0, -10.0}}, &rng);
  const RadarFrame f = p.Process(cube, Eigen::Isometry3d::Identity(), 0.0);
  CHECK(f.RawBytes() == 512u * 64u * 12u * 8u);
  CHECK(f.RawBytes() == static_cast<std::size_t>(c.RawBytesPerFrame()));
  CHECK(f.PointBytes() == f.points.size() * 20u);
  const auto& map = f.range_doppler;
  CHECK(map.range_bins == 512);
  CHECK(map.doppler_bins == 64);
  CHECK(map.range_bin_m == Approx(p.range_bin_m()));
  CHECK(map.velocity_bin_mps == Approx(p.velocity_bin_mps()));
  REQUIRE(map.power_db.size() == 512u * 64u);
  // Noise-only cells average 1 (0 dB) in linear power; the mean of the
  // log of a Gamma(12) variable of mean 1 is psi(12) - ln 12 = -0.0425 nepers.
  double mean_db = 0.0;
  int n = 0;
  for (int d = 0; d < 64; ++d)
    for (int r = 300; r < 500; ++r)
      if (d != 32) mean_db += map.power_db[d * 512 + r], ++n;
  CHECK(mean_db / n == Approx(10.0 / std::log(10.0) * -0.0425).margin(0.05));
  // Same cube, several threads at once: the same frame.
  std::vector<RadarFrame> frames(3);
  std::vector<std::thread> threads;
  for (auto& out : frames)
    threads.emplace_back([&] { out = p.Process(cube, Eigen::Isometry3d::Identity(), 0.0); });
  for (auto& t : threads) t.join();
  for (const RadarFrame& g : frames) {
    REQUIRE(g.points.size() == f.points.size());
    for (std::size_t i = 0; i < f.points.size(); ++i) {
      CHECK(g.points[i].x_m == f.points[i].x_m);
      CHECK(g.points[i].snr_db == f.points[i].snr_db);
    }
    CHECK(g.range_doppler.power_db == map.power_db);
  }
}

TEST_CASE("RadarProcessor: arrays with one row or one column estimate the angle they can",
          "[sensors]") {
  for (int rows : {1, 3}) {
    FmcwRadarConfig c;
    c.nx = rows == 1 ? 8 : 1;
    c.ny = rows;
    for (AngleMethod method : {AngleMethod::kMusic, AngleMethod::kEsprit, AngleMethod::kBeamscan}) {
      c.processing.angle_method = method;
      const RadarProcessor p(c);
      RngStream rng(20, "line");
      // A horizontal line of 8 sees azimuth only; a vertical line of 3, elevation only.
      const Target t{30.0, 2.0, rows == 1 ? 25.0 : 0.0, rows == 1 ? 0.0 : -12.0, -5.0};
      const RadarFrame f =
          p.Process(ClosedFormCube(c, {t}, &rng), Eigen::Isometry3d::Identity(), 0.0);
      REQUIRE(!f.points.empty());
      const Eigen::Vector3d u =
          Eigen::Vector3d(f.points[0].x_m, f.points[0].y_m, f.points[0].z_m).normalized();
      INFO("rows " << rows << " method " << static_cast<int>(method));
      CHECK(AngleBetweenRad(u, Direction(t.az_deg * kDeg, t.el_deg * kDeg)) < 2.0 * kDeg);
    }
  }
}

TEST_CASE("EncodeRangeDopplerPng: near range at the bottom, zero velocity in the middle",
          "[sensors]") {
  uavsim::sensors::RangeDopplerMap map;
  map.range_bins = 128;
  map.doppler_bins = 64;
  map.range_bin_m = 0.2;
  map.velocity_bin_mps = 0.4;
  map.power_db.assign(128 * 64, -100.0f);
  // One hot cell: near range (bin 10 of 128), receding (Doppler bin 48 > 32).
  map.power_db[48 * 128 + 10] = 0.0f;
  const std::vector<std::uint8_t> png = uavsim::sensors::EncodeRangeDopplerPng(map);
  REQUIRE(png.size() > 8);
  CHECK(png[1] == 'P');
  const cv::Mat img = cv::imdecode(png, cv::IMREAD_COLOR);
  REQUIRE(!img.empty());
  CHECK(img.cols >= 512);
  CHECK(img.rows >= 512);
  // The hot cell is viridis' top colour (yellow: B low, G and R high); the
  // rest, 100 dB down, its bottom (dark purple). Look left of the colour bar
  // (the right margin) for the yellow pixels.
  const int plot_cols = img.cols - 100;
  double sx = 0.0, sy = 0.0;
  int n = 0, dark = 0;
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < plot_cols; ++x) {
      const cv::Vec3b bgr = img.at<cv::Vec3b>(y, x);
      if (bgr[0] < 80 && bgr[1] > 200 && bgr[2] > 200) sx += x, sy += y, ++n;
      if (bgr[0] + bgr[1] + bgr[2] < 200) ++dark;
    }
  REQUIRE(n > 0);
  CHECK(sy / n > 0.75 * img.rows);  // near range: at the bottom
  CHECK(sx / n > 0.6 * plot_cols);  // receding: right of zero velocity
  CHECK(dark > img.rows * plot_cols / 2);
  CHECK_THROWS_AS(uavsim::sensors::EncodeRangeDopplerPng(uavsim::sensors::RangeDopplerMap{}),
                  std::invalid_argument);
}

// ----- End to end: FmcwRadar's synthesis, then this processing. -----

namespace {

uavsim::sensors::Scatterer PointScatterer(const Eigen::Vector3d& p_W, const Eigen::Vector3d& v_W,
                                          double rcs_m2) {
  uavsim::sensors::Scatterer s;
  s.position_m = p_W;
  s.velocity_mps = v_W;
  s.rcs_m2 = rcs_m2;
  return s;
}

}  // namespace

TEST_CASE("FmcwRadar + RadarProcessor: a scatterer comes back at its world position and speed",
          "[sensors]") {
  FmcwRadarConfig c;
  c.pose.position_m = {-30.0, 30.0, 1.5};
  c.pose.rpy_deg = {0.0, -30.0, -45.0};  // the default scenario's radar
  const Eigen::Isometry3d X_WR = c.pose.ToIsometry();
  uavsim::core::WorldGeometry empty;
  uavsim::sensors::RaycastScene scene(empty);
  const FmcwRadar radar(c, scene);
  const RadarProcessor p(c);
  RngStream noise(21, "radar1");
  const Eigen::Vector3d origin = X_WR.translation();
  for (const Eigen::Vector3d& p_W :
       {Eigen::Vector3d(-10.0, 15.0, 20.0), Eigen::Vector3d(-5.0, 5.0, 12.0)}) {
    const Eigen::Vector3d v_W(4.0, -3.0, 1.0);
    // Radial velocity: the velocity along the line of sight, receding > 0.
    const double v_radial = v_W.dot((p_W - origin).normalized());
    // 10 m^2 (a car): the angle error (about 0.1 deg here) stays well inside
    // the tolerance; the angle statistics are tested above.
    const RadarCube cube = radar.Synthesize({PointScatterer(p_W, v_W, 10.0)}, {}, noise);
    const RadarFrame f = p.Process(cube, X_WR, 0.0);
    REQUIRE(!f.points.empty());
    const Eigen::Vector3d got(f.points[0].x_m, f.points[0].y_m, f.points[0].z_m);
    INFO("expected " << p_W.transpose() << " v " << v_radial << ", got " << got.transpose() << " v "
                     << f.points[0].radial_velocity_mps << " snr " << f.points[0].snr_db);
    CHECK((got - p_W).norm() < 0.2);
    CHECK(f.points[0].radial_velocity_mps == Approx(v_radial).margin(0.25 * p.velocity_bin_mps()));
  }
}

TEST_CASE("FmcwRadar + RadarProcessor: the detection SNR falls as 40 log10 R within 1 dB",
          "[sensors]") {
  // Targets on range bins (no scalloping) at R and 2R, same direction and
  // an on-bin velocity; 40 log10 2 = 12.04 dB between them.
  const FmcwRadarConfig c;
  uavsim::core::WorldGeometry empty;
  uavsim::sensors::RaycastScene scene(empty);
  const FmcwRadar radar(c, scene);
  const RadarProcessor p(c);
  const Eigen::Vector3d u = Direction(15.0 * kDeg, 5.0 * kDeg);
  const double v = 6.0 * p.velocity_bin_mps();
  RngStream noise(22, "radar1");
  for (int bin : {40, 60, 100}) {
    double snr_db[2];
    for (int k = 0; k < 2; ++k) {
      const double range = (k + 1) * bin * p.range_bin_m();
      const RadarCube cube = radar.Synthesize({PointScatterer(range * u, v * u, 1.0)}, {}, noise);
      const std::vector<RadarDetection> dets = p.Detect(p.Transform(cube));
      REQUIRE(!dets.empty());
      REQUIRE(dets[0].range_bin == (k + 1) * bin);
      snr_db[k] = dets[0].snr_db;
    }
    INFO("R = " << bin * p.range_bin_m() << " m: " << snr_db[0] << " dB, at 2R: " << snr_db[1]);
    CHECK(snr_db[0] - snr_db[1] == Approx(40.0 * std::log10(2.0)).margin(1.0));
  }
}

TEST_CASE("FmcwRadar + RadarProcessor: a flying quadrotor over the ground is a point at its place",
          "[sensors]") {
  // Rays -> scatterers -> IF cube -> points. The ground is static and goes
  // with the clutter; the quadrotor (0.5 x 0.5 x 0.2 m, ~0.04 m^2) moves.
  uavsim::core::WorldGeometry world;
  uavsim::core::TriangleMesh ground;
  ground.name = "ground";
  ground.material = uavsim::core::kMaterialGround;
  ground.vertices_m = {
      {-10.0f, -60.0f, 0.0f}, {100.0f, -60.0f, 0.0f}, {100.0f, 60.0f, 0.0f}, {-10.0f, 60.0f, 0.0f}};
  ground.triangles = {{0, 1, 2}, {0, 2, 3}};
  world.meshes.push_back(ground);
  uavsim::sensors::RaycastScene scene(world);
  const Eigen::Vector3d p0(14.0, 3.0, 6.0), v(-4.0, 3.0, 0.5);
  scene.AddMovingObject(uavsim::core::MakeQuadrotorMesh({0.5, 0.5, 0.2}), [&](double t) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = p0 + v * t;
    return X;
  });
  FmcwRadarConfig c;
  c.pose.position_m = {0.0, 0.0, 1.5};
  c.pose.rpy_deg = {0.0, -15.0, 0.0};  // tilted up
  const Eigen::Isometry3d X_WR = c.pose.ToIsometry();
  const FmcwRadar radar(c, scene);
  const RadarProcessor p(c);
  RngStream noise(23, "radar1");
  for (double t : {0.0, 0.4}) {
    scene.SetTime(t);
    const RadarFrame f = p.Process(radar.Synthesize(radar.FindScatterers(t), {}, noise), X_WR, t);
    const Eigen::Vector3d centre = p0 + v * t;
    const double v_radial = v.dot((centre - X_WR.translation()).normalized());
    REQUIRE(!f.points.empty());
    const auto& pt = f.points[0];
    const Eigen::Vector3d got(pt.x_m, pt.y_m, pt.z_m);
    INFO("t " << t << ": UAV at " << centre.transpose() << " v " << v_radial << "; strongest point "
              << got.transpose() << " v " << pt.radial_velocity_mps << " snr " << pt.snr_db
              << " of " << f.points.size());
    CHECK((got - centre).norm() < 0.6);
    CHECK(std::abs(pt.radial_velocity_mps - v_radial) < p.velocity_bin_mps());
    // Whatever else was detected is not static ground.
    for (const auto& q : f.points)
      CHECK(std::abs(q.radial_velocity_mps) > 0.5 * p.velocity_bin_mps());
  }
}

TEST_CASE("RadarProcessor: a termination request stops processing between detections",
          "[sensors]") {
  const FmcwRadarConfig c;
  const RadarProcessor p(c);
  RngStream rng(5, "interrupt");
  const RadarCube cube = ClosedFormCube(c, {{30.0, 4.0, 10.0, 5.0, -15.0}}, &rng);
  REQUIRE_FALSE(p.Process(cube, Eigen::Isometry3d::Identity(), 0.0).points.empty());
  uavsim::core::RequestInterrupt();
  CHECK_THROWS_AS(p.Process(cube, Eigen::Isometry3d::Identity(), 0.0), uavsim::core::Interrupted);
  uavsim::core::ClearInterrupt();
  CHECK_FALSE(p.Process(cube, Eigen::Isometry3d::Identity(), 0.0).points.empty());
}
