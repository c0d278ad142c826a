#include "apps/bench/bench_beam.h"

#include <cmath>
#include <cstdint>
#include <iomanip>
#include <map>
#include <string>
#include <vector>

#include "apps/bench/gbench.h"
#include "channel/base_station_config.h"
#include "channel/beam_channel.h"
#include "channel/beamformer.h"
#include "channel/path_oracle.h"
#include "core/physical_constants.h"
#include "core/rng.h"
#include "core/world_geometry.h"

namespace uavsim::sim {
namespace {

using core::kPi;
constexpr std::uint64_t kSeed = 1;
constexpr std::size_t kSamples = 4096;  // estimates along the orbit, one sweep

// Facades that block nothing: the cost measured is the channel's own.
class OpenFacades : public channel::PathOracle {
 public:
  explicit OpenFacades(std::vector<core::Facade> facades) : facades_(std::move(facades)) {}
  bool Blocked(const Eigen::Vector3d&, const Eigen::Vector3d&) const override { return false; }
  const std::vector<core::Facade>& Reflectors() const override { return facades_; }

 private:
  std::vector<core::Facade> facades_;
};

// `count` inward-facing walls on squares around the origin (4 per square,
// squares 40 m, 50 m, ... from the centre), like the faces of the streets
// around the default central plaza.
std::vector<core::Facade> Walls(int count) {
  std::vector<core::Facade> walls;
  for (int i = 0; i < count; ++i) {
    const double distance_m = 40.0 + 10.0 * (i / 4);
    const double angle = kPi / 2.0 * (i % 4);
    const Eigen::Vector3d out(std::cos(angle), std::sin(angle), 0.0);
    core::Facade f;
    f.center_m = distance_m * out + Eigen::Vector3d(0.0, 0.0, 15.0);
    f.normal = -out;
    f.u_axis = Eigen::Vector3d(-out.y(), out.x(), 0.0);
    f.half_width_m = 30.0;
    f.half_height_m = 15.0;
    f.material = i % 2 ? core::kMaterialGlass : core::kMaterialConcrete;
    walls.push_back(f);
  }
  return walls;
}

struct Sample {
  Eigen::Vector3d truth;
  Eigen::Vector3d estimate;
};

// The default orbit (centre (0, 0, 30), radius 25 m) with 1 m estimate noise.
std::vector<Sample> Samples(std::size_t n) {
  core::RngStream rng(kSeed, "bench/beam");
  std::vector<Sample> s(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * static_cast<double>(i) / static_cast<double>(n);
    s[i].truth = Eigen::Vector3d(25.0 * std::cos(a), 25.0 * std::sin(a), 30.0);
    s[i].estimate = s[i].truth + Eigen::Vector3d(rng.Normal(), rng.Normal(), rng.Normal());
  }
  return s;
}

struct Row {
  int m;  // m x m array
  int walls;
  bool dft;
  bool scorer;  // whole DownlinkScorer windows
};

struct Measured {
  std::int64_t evaluations = 0;
  double seconds = 0.0;
  double evaluations_per_s = 0.0;
  double mean_gain = 0.0;
};

constexpr double kWarmUpS = 0.05, kMinTimeS = 0.5;

// Google Benchmark times the evaluations (an iteration is one), in whole
// sweeps over `samples` so that the mean gain weighs every sample alike.
Measured MeasureRow(const Row& row, const std::vector<Sample>& samples) {
  channel::BaseStationConfig bs;
  bs.upa.mx = bs.upa.my = row.m;
  bs.path_model = row.walls ? channel::PathModel::kImage : channel::PathModel::kLosOnly;
  bs.beams = {"steered", "dft"};
  const OpenFacades world(Walls(row.walls));
  const channel::BeamChannel channel(bs);
  const channel::DftCodebook codebook(channel.upa(), bs.dft_oversampling);
  channel::DownlinkScorer scorer(bs, 0.0, {"uavloc", "ekf"}, channel::SnrGridDb(-10, 30, 2),
                                 core::RngStream(kSeed, "bench/beam/scorer"));
  channel::DownlinkChannel h;
  Eigen::VectorXcd f;
  const auto evaluate = [&](const Sample& s) {
    if (row.scorer) {
      scorer.AddWindow(s.truth, {{"uavloc", s.estimate}, {"ekf", s.estimate}}, world);
      return 0.0;
    }
    channel.RealizeInto(s.truth, world, nullptr, &h);
    if (row.dft)
      codebook.BeamAtInto(bs.position_m, s.estimate, &f);
    else
      channel::SteeredBeamInto(channel.upa(), bs.position_m, s.estimate, &f);
    return channel::BeamGain(h.h, f);
  };
  gbench::Register(
      "beam",
      [&](benchmark::State& state) {
        double gain_sum = 0.0;
        while (state.KeepRunningBatch(static_cast<benchmark::IterationCount>(samples.size())))
          for (const Sample& s : samples) gain_sum += evaluate(s);
        benchmark::DoNotOptimize(gain_sum);
        state.counters["evaluations"] =
            benchmark::Counter(1.0, benchmark::Counter::kIsIterationInvariantRate);
        // A checksum of the work; the scorer's is over every window it scored.
        state.counters["mean_gain"] = row.scorer
                                          ? scorer.rates().MeanGain("uavloc")
                                          : gain_sum / static_cast<double>(state.iterations());
      })
      ->Unit(benchmark::kMicrosecond)
      ->MinWarmUpTime(kWarmUpS)
      ->MinTime(kMinTimeS);
  const gbench::Measurement m = gbench::RunSingle().Fastest();
  return {m.iterations, m.seconds(), m.Counter("evaluations"), m.Counter("mean_gain")};
}

}  // namespace

int BenchBeam(bool quiet, std::ostream& out) {
  if (!quiet)
    out << "Downlink beam evaluations (channel at the true position + beam at an estimate + "
           "|h^H f|^2), closed-form world, one core\n";
  const std::vector<Row> rows = {
      {8, 0, false, false},  {8, 8, false, false},  {8, 64, false, false}, {8, 8, true, false},
      {16, 0, false, false}, {16, 8, false, false}, {32, 8, false, false}, {8, 8, false, true},
  };
  out << std::left << std::setw(7) << "array" << std::setw(16) << "paths" << std::setw(10) << "beam"
      << std::right << std::setw(12) << "evaluations" << std::setw(9) << "seconds" << std::setw(14)
      << "k evals/s" << std::setw(12) << "mean gain"
      << "\n";
  const std::vector<Sample> samples = Samples(kSamples);
  for (const Row& row : rows) {
    const Measured r = MeasureRow(row, samples);
    const std::string array = std::to_string(row.m) + "x" + std::to_string(row.m);
    const std::string paths =
        row.walls ? "image, " + std::to_string(row.walls) + " walls" : "LOS only";
    const std::string beam = row.scorer ? "window" : row.dft ? "dft" : "steered";
    out << std::left << std::setw(7) << array << std::setw(16) << paths << std::setw(10) << beam
        << std::right << std::setw(12) << r.evaluations << std::setw(9) << std::fixed
        << std::setprecision(3) << r.seconds << std::setw(14) << std::setprecision(1)
        << r.evaluations_per_s / 1e3 << std::setw(12) << std::setprecision(2) << r.mean_gain
        << std::defaultfloat << "\n"
        << std::flush;
  }
  return 0;
}

}  // namespace uavsim::sim
