#include "apps/bench/gbench.h"

#include <algorithm>
#include <mutex>
#include <stdexcept>
#include <utility>

namespace uavsim::sim::gbench {
namespace {

// Names registered since the last run, in order (Google Benchmark keeps the
// benchmarks themselves).
std::vector<std::string>& Registered() {
  static std::vector<std::string> names;
  return names;
}

// A fake command line of the program name alone: Google Benchmark's flags
// must not be parsed from uavsim's arguments. argv[0] is kept by the library
// (as the executable's name), hence static storage.
void InitializeOnce() {
  static std::once_flag once;
  std::call_once(once, [] {
    static char program[] = "uavsim";
    static char* argv[] = {program, nullptr};
    int argc = 1;
    benchmark::Initialize(&argc, argv);
  });
}

Measurement ToMeasurement(const benchmark::BenchmarkReporter::Run& run) {
  const double per_s = benchmark::GetTimeUnitMultiplier(run.time_unit);
  Measurement m;
  m.iterations = run.iterations;
  m.real_s_per_iteration = run.GetAdjustedRealTime() / per_s;
  m.cpu_s_per_iteration = run.GetAdjustedCPUTime() / per_s;
  for (const auto& [name, counter] : run.counters) m.counters[name] = counter.value;
  return m;
}

// Collects the runs instead of printing them: each bench writes its own table.
class Collector : public benchmark::BenchmarkReporter {
 public:
  bool ReportContext(const Context&) override { return true; }

  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      const std::string& name = run.run_name.function_name;
      if (run.error_occurred) {
        errors_.push_back(name + ": " + run.error_message);
        continue;
      }
      Result& r = results_[name];
      r.name = name;
      if (run.run_type == Run::RT_Aggregate)
        r.aggregates[run.aggregate_name] = ToMeasurement(run);
      else
        r.repetitions.push_back(ToMeasurement(run));
    }
  }

  const std::vector<std::string>& errors() const { return errors_; }
  std::map<std::string, Result>& results() { return results_; }

 private:
  std::map<std::string, Result> results_;
  std::vector<std::string> errors_;
};

// Clears both registries however RunRegistered ends.
struct ClearOnExit {
  ~ClearOnExit() {
    benchmark::ClearRegisteredBenchmarks();
    Registered().clear();
  }
};

}  // namespace

double Measurement::Counter(const std::string& name) const {
  const auto it = counters.find(name);
  if (it == counters.end()) throw std::out_of_range("benchmark counter '" + name + "' not set");
  return it->second;
}

const Measurement& Result::Fastest() const {
  if (repetitions.empty()) throw std::out_of_range("benchmark '" + name + "': no repetition");
  return *std::min_element(repetitions.begin(), repetitions.end(),
                           [](const Measurement& a, const Measurement& b) {
                             return a.real_s_per_iteration < b.real_s_per_iteration;
                           });
}

const Measurement& Result::Aggregate(const std::string& aggregate) const {
  const auto it = aggregates.find(aggregate);
  if (it == aggregates.end())
    throw std::out_of_range("benchmark '" + name + "': no aggregate '" + aggregate + "'");
  return it->second;
}

benchmark::internal::Benchmark* Register(const std::string& name,
                                         std::function<void(benchmark::State&)> body) {
  std::vector<std::string>& names = Registered();
  if (std::find(names.begin(), names.end(), name) != names.end())
    throw std::logic_error("benchmark '" + name + "' registered twice");
  names.push_back(name);
  return benchmark::RegisterBenchmark(name.c_str(), std::move(body))->UseRealTime();
}

std::vector<Result> RunRegistered() {
  const ClearOnExit clear;
  InitializeOnce();
  Collector collector;
  // "." matches every registered benchmark, whatever BENCHMARK_FILTER says.
  benchmark::RunSpecifiedBenchmarks(&collector, ".");
  if (!collector.errors().empty()) throw std::runtime_error(collector.errors().front());
  std::vector<Result> ordered;
  for (const std::string& name : Registered()) {
    auto it = collector.results().find(name);
    if (it == collector.results().end() || it->second.repetitions.empty())
      throw std::runtime_error("benchmark '" + name + "' produced no result");
    ordered.push_back(std::move(it->second));
  }
  return ordered;
}

Result RunSingle() {
  if (Registered().size() != 1) {
    const ClearOnExit clear;
    throw std::logic_error("gbench::RunSingle: " + std::to_string(Registered().size()) +
                           " benchmarks registered, expected 1");
  }
  return RunRegistered().front();
}

}  // namespace uavsim::sim::gbench
