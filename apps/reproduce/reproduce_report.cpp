#include "apps/reproduce/reproduce_report.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>

#include "apps/bench/bench_flops.h"
#include "apps/reproduce/reproduce_claim_table.h"
#include "apps/reproduce/reproduce_verdict_file.h"
#include "channel/beamformer.h"
#include "channel/upa.h"
#include "core/atomic_file.h"
#include "core/json_io.h"
#include "pipeline/variants.h"
#include "results/bar_plot.h"
#include "results/csv.h"
#include "results/plot.h"
#include "sim/version.h"

namespace uavsim::sim {
namespace {

namespace fs = std::filesystem;
using core::Json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A bar of one number (a count, a rate, the paper's value): no interval.
SeedStat SingleValue(double x) {
  SeedStat s;
  s.mean = x;
  s.n = 1;
  return s;
}

const char* const kModalities[] = {"camera", "lidar", "radar"};

// ---------------------------------------------------------------------------
// Statistics over seeds.

using Seeds = std::vector<double>;  // [seed - 1]; NaN where missing
using Stat = SeedStat;

Stat Summarise(const Seeds& v) { return SummariseSeeds(v); }

std::string Fixed(double x, int decimals) {
  return std::isfinite(x) ? results::FormatFixed(x, decimals) : "";
}

// "6.82 ± 0.41" (or "6.82" for one seed, "-" for none).
std::string MeanCi(const Stat& s, int decimals = 2) { return MeanCiText(s, decimals); }

using Claim = ReproduceClaim;
using Block = ReportBlock;
using Document = ReportDocument;

// ---------------------------------------------------------------------------
// The trainings' results.

class Arms {
 public:
  Arms(const std::string& dir, const ReproducePlan& plan) : dir_(dir), plan_(plan) {
    for (const ReproduceArm& a : plan.arms) {
      const std::string file = (fs::path(dir) / "models" / a.id / "training_report.json").string();
      reports_[a.id] = core::LoadJsonFile(file);
    }
  }
  int seeds() const { return plan_.seeds; }
  int z0() const { return plan_.scenario_latent_dim; }

  // The held-out RMSE of variant's method on a subset, per seed.
  Seeds Rmse(const std::string& variant, const std::string& subset, bool frame = false) const {
    Seeds out;
    const std::string method = pipeline::VariantMethod(variant);
    for (int s = 1; s <= seeds(); ++s) {
      const Json* r = Find(Id(variant, z0(), s, frame));
      double v = kNaN;
      if (r && r->contains("test") && (*r)["test"].contains(method)) {
        const Json& e = (*r)["test"][method];
        if (e.contains(subset) && e[subset]["rmse_m"].is_number())
          v = e[subset]["rmse_m"].get<double>();
      }
      out.push_back(v);
    }
    return out;
  }
  // Each node's decoder alone at latent size z, per seed: over every
  // held-out observation (`what` "all"), over those holding the target
  // ("on_target"), or the centroid of those same observations ("centroid";
  // NaN for reports written before these were recorded).
  Seeds Decoder(const std::string& variant, int z, const std::string& modality,
                const std::string& what = "all") const {
    Seeds out;
    const Json::json_pointer field(what == "all"         ? "/rmse_m"
                                   : what == "on_target" ? "/on_target/rmse_m"
                                                         : "/centroid_on_target_m");
    for (int s = 1; s <= seeds(); ++s) {
      const Json* r = Find(Id(variant, z, s, false));
      double v = kNaN;
      if (r && r->contains("test_decoder") && (*r)["test_decoder"].contains(modality)) {
        const Json& d = (*r)["test_decoder"][modality];
        if (d.contains(field) && d.at(field).is_number()) v = d.at(field).get<double>();
      }
      out.push_back(v);
    }
    return out;
  }
  std::string ModelDir(const std::string& variant, int s) const {
    return (fs::path(dir_) / "models" / Id(variant, z0(), s, false)).string();
  }
  double TrainingSeconds() const {
    double t = 0.0;
    for (const auto& [id, r] : reports_)
      for (const Json& st : r.value("stages", Json::array())) t += st.value("seconds", 0.0);
    return t;
  }
  std::size_t count() const { return reports_.size(); }

  // Every training stage against its budget (the model's resolved training
  // config): a row of trainings.csv each. A stage reached its validation
  // plateau when `patience` epochs had passed without a better validation
  // loss when it stopped (by its patience or at the cap).
  struct StageBudget {
    std::string id, stage;
    bool stage1 = false;  // a node's encoder (camera, lidar, radar), else stage 2
    int epochs = 0, best_epoch = 0, max_epochs = 0, patience = 0;
    bool plateau() const { return epochs - best_epoch >= patience; }
  };
  std::vector<StageBudget> Budgets() const {
    std::vector<StageBudget> out;
    for (const auto& [id, r] : reports_) {
      const Json manifest =
          core::LoadJsonFile((fs::path(dir_) / "models" / id / "model.json").string());
      const Json& t = manifest.at("training");
      for (const Json& st : r.value("stages", Json::array())) {
        StageBudget b;
        b.id = id;
        b.stage = st.value("name", "");
        b.stage1 = b.stage == "camera" || b.stage == "lidar" || b.stage == "radar";
        b.epochs = st.value("epochs", 0);
        b.best_epoch = st.value("best_epoch", 0);
        b.max_epochs = t.value(b.stage1 ? "stage1_max_epochs" : "stage2_max_epochs", 0);
        b.patience = t.value(b.stage1 ? "stage1_patience" : "stage2_patience", 0);
        out.push_back(b);
      }
    }
    return out;
  }

 private:
  static std::string Id(const std::string& variant, int z, int s, bool frame) {
    return variant + "-z" + std::to_string(z) + "-s" + std::to_string(s) + (frame ? "-frame" : "");
  }
  const Json* Find(const std::string& id) const {
    const auto it = reports_.find(id);
    return it == reports_.end() ? nullptr : &it->second;
  }
  std::string dir_;
  const ReproducePlan& plan_;
  std::map<std::string, Json> reports_;
};

// ---------------------------------------------------------------------------
// Artefact writers.

struct Writer {
  std::string dir;
  std::vector<std::string> warnings;
  Document doc;
  ClaimMeasurements measured;  // what the claims read (reproduce_claim_table.h)

  void Csv(const std::string& name, const std::string& text) {
    core::WriteFileAtomic((fs::path(dir) / name).string(), text);
  }
  void Warn(const std::string& name, const std::string& message) {
    if (!message.empty()) warnings.push_back(name + ": " + message);
  }
  // Under "table/series/category"; `table` is the artefact file's prefix.
  void Measure(const std::string& table, const std::string& series, const std::string& category,
               const Seeds& per_seed) {
    measured.seeds[ClaimMeasurements::Key(table, series, category)] = per_seed;
  }
  void MeasureNumber(const std::string& table, const std::string& series,
                     const std::string& category, double x) {
    measured.numbers[ClaimMeasurements::Key(table, series, category)] = x;
  }
};

// One bar per (category, series) with its CI, as a long CSV and its PNG.
struct Bar {
  std::string category, series;
  Stat value;
};

// name.csv, and its bars in `png` ("": name.png).
void WriteBars(Writer& w, const std::string& name, const std::string& category_column,
               const std::string& value_column, const std::vector<Bar>& bars,
               const std::string& title, const std::string& y_label, bool log_y,
               const std::string& x_label, const std::string& png = "") {
  std::ostringstream csv;
  csv << category_column << ",series," << value_column << ",ci95,seeds\n";
  for (const Bar& b : bars)
    csv << b.category << "," << b.series << "," << Fixed(b.value.mean, 6) << ","
        << Fixed(b.value.ci95, 6) << "," << b.value.n << "\n";
  w.Csv(name + ".csv", csv.str());
  results::BarPlotSpec spec;
  spec.title = title;
  spec.x_label = x_label;
  spec.y_label = y_label;
  spec.category_column = category_column;
  spec.series_column = "series";
  spec.y_column = value_column;
  spec.ci95_column = "ci95";
  spec.log_y = log_y;
  const std::string png_name = png.empty() ? name + ".png" : png;
  spec.png_path = (fs::path(w.dir) / png_name).string();
  w.Warn(png_name, results::PlotBars((fs::path(w.dir) / (name + ".csv")).string(), spec));
}

// A table of subsets x series ("mean ± ci" cells) for the report.
std::vector<std::vector<std::string>> SubsetTable(
    const std::vector<std::pair<std::string, std::map<std::string, Stat>>>& series) {
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> head{"subset"};
  for (const auto& [label, values] : series) head.push_back(label + " (m)");
  rows.push_back(head);
  for (const std::string& subset : ModalitySubsets()) {
    std::vector<std::string> row{subset};
    for (const auto& [label, values] : series) {
      const auto it = values.find(subset);
      row.push_back(it == values.end() ? "-" : MeanCi(it->second));
    }
    rows.push_back(row);
  }
  return rows;
}

// A figure of the held-out RMSE per modality subset, one series per
// (label, variant[, frame split]), each subset's per-seed values measured
// under "<prefix of name>/<label>/<subset>" and returned by label and subset.
struct Series {
  std::string label;
  std::string variant;
  bool frame = false;
};
using SubsetValues = std::map<std::string, std::map<std::string, Seeds>>;
SubsetValues SubsetFigure(Writer& w, const Arms& arms, const std::string& name,
                          const std::string& title, const std::vector<Series>& series) {
  SubsetValues values;
  std::vector<Bar> bars;
  std::vector<std::pair<std::string, std::map<std::string, Stat>>> table;
  for (const Series& s : series) {
    std::map<std::string, Stat> stats;
    for (const std::string& subset : ModalitySubsets()) {
      values[s.label][subset] = arms.Rmse(s.variant, subset, s.frame);
      w.Measure(name.substr(0, name.find('_')), s.label, subset, values[s.label][subset]);
      stats[subset] = Summarise(values[s.label][subset]);
      bars.push_back({subset, s.label, stats[subset]});
    }
    table.emplace_back(s.label, stats);
  }
  WriteBars(w, name, "subset", "rmse_m", bars, title, "held-out RMSE (m)", false,
            "modalities available at the edge");
  w.doc.Image(name + ".png", title);
  w.doc.Table(SubsetTable(table));
  return values;
}

// ---------------------------------------------------------------------------
// Figs. 7-9.

// The series of Figs. 7-9: label, variant, what of each node's decoder
// (Arms::Decoder); the last two are the information limit, drawn but not
// compared.
struct DecoderScheme {
  const char* label;
  const char* variant;
  const char* what;
};
const DecoderScheme kDecoderSchemes[] = {{"IB", "paper", "all"},
                                         {"MLP", "mlp_bottleneck", "all"},
                                         {"IB without pre-processing", "raw", "all"},
                                         {"IB on target", "paper", "on_target"},
                                         {"centroid on target", "paper", "centroid"}};

// name.png from name_limit.csv: every scheme's RMSE vs z.
void PlotDecoderFigure(Writer& w, const std::string& name, const std::string& title) {
  results::PlotSpec spec;
  spec.title = title;
  spec.x_label = "latent size z";
  spec.y_label = "held-out RMSE (m)";
  spec.x_column = "z";
  spec.y_column = "rmse_m";
  spec.group_column = "scheme";
  spec.y_error_column = "ci95";
  spec.skip_empty_y = true;
  spec.log_x = true;
  spec.y_min_zero = true;
  spec.key_below = true;
  spec.png_path = (fs::path(w.dir) / (name + ".png")).string();
  w.Warn(name + ".png", results::PlotCsv((fs::path(w.dir) / (name + "_limit.csv")).string(), spec));
}

// One modality's figure (name.csv: the compared schemes, the claims' and
// their margin's table; name_limit.csv: the same with the information
// limit's two series, for the plot) and its table.
void DecoderFigure(Writer& w, const Arms& arms, const ReproducePlan& plan,
                   const std::string& modality, const std::string& figure,
                   const std::string& name) {
  std::ostringstream csv, with_limit;
  csv << "z,scheme,rmse_m,ci95,seeds\n";
  with_limit << "z,scheme,rmse_m,ci95,seeds\n";
  std::vector<std::vector<std::string>> table{{"z"}};
  for (const DecoderScheme& scheme : kDecoderSchemes)
    table[0].push_back(std::string(scheme.label) + " (m)");
  for (int z : plan.latent_dims) {
    std::vector<std::string> row{std::to_string(z)};
    for (const DecoderScheme& scheme : kDecoderSchemes) {
      const Seeds v = arms.Decoder(scheme.variant, z, modality, scheme.what);
      w.Measure(name.substr(0, name.find('_')), scheme.label, std::to_string(z), v);
      const Stat s = Summarise(v);
      std::ostringstream line;
      line << z << "," << scheme.label << "," << Fixed(s.mean, 6) << "," << Fixed(s.ci95, 6) << ","
           << s.n << "\n";
      if (std::string(scheme.what) == "all") csv << line.str();
      with_limit << line.str();
      row.push_back(MeanCi(s));
    }
    table.push_back(row);
  }
  w.Csv(name + ".csv", csv.str());
  w.Csv(name + "_limit.csv", with_limit.str());
  const std::string title = figure + ": " + modality + " decoder alone vs latent size";
  PlotDecoderFigure(w, name, title);
  w.doc.Image(name + ".png", title);
  w.doc.Table(table);
}

void DecoderFigures(Writer& w, const Arms& arms, const ReproducePlan& plan) {
  w.doc.Heading("Figs. 7-9: each node's decoder alone vs latent size z");
  w.doc.Text(
      "Each node's IB-CC encoder-decoder on its own (no fusion, no alignment): the RMSE of the "
      "position it decodes from each held-out observation against the truth at the capture. "
      "IB: the paper's bottleneck; MLP: its baseline of equal depth and parameter count; "
      "IB without pre-processing: the nodes encode raw data. Beside them the information "
      "limit: IB on the observations that hold the target (a point within 1 m, radar 3 m, a "
      "camera ray within 1 m) and, on the same observations, the cloud's centroid (the "
      "camera: its ray at the true range).");
  const char* figure[] = {"Fig. 7", "Fig. 8", "Fig. 9"};
  const char* file[] = {"fig07_camera_z", "fig08_lidar_z", "fig09_radar_z"};
  for (int m = 0; m < 3; ++m) DecoderFigure(w, arms, plan, kModalities[m], figure[m], file[m]);
}

// ---------------------------------------------------------------------------
// Tab. II.

double Percent(double x, double of) { return of > 0 ? 100.0 * x / of : kNaN; }

// "13261.0 (20.8175 %)": a rate (KB/s) and its percentage of `of`.
std::string RateCell(double x, double of) {
  return results::FormatFixed(x, x < 10 ? 3 : 1) + " (" + Fixed(Percent(x, of), 4) + " %)";
}

// Table II as it is built: its CSV, the report's table, the bars of our rates.
struct RateRows {
  std::ostringstream csv;
  std::vector<std::vector<std::string>> table;
  std::vector<Bar> bars;
  double max_ib_16 = 0.0;  // KB/s: the largest IB rate of any modality at z <= 16
};

// Our rates of one modality (the runs' metrics by z), at the paper's IB
// columns; measures its pre-processed share (%).
void AddOurRates(Writer& w, RateRows& r, std::map<int, Json>& metrics, int z0,
                 const char* modality) {
  const Json& m = metrics[z0]["data_rate_kBps"][modality];
  const double raw = m["raw"].get<double>(), pre = m["preprocessed"].get<double>();
  w.MeasureNumber("table2", "pre-processed share", modality, Percent(pre, raw));
  std::vector<std::string> ours{modality, "uavsim", results::FormatFixed(raw, 1),
                                RateCell(pre, raw)};
  r.csv << modality << ",uavsim,original,," << Fixed(raw, 6) << ",100\n";
  r.csv << modality << ",uavsim,preprocessed,," << Fixed(pre, 6) << ","
        << Fixed(Percent(pre, raw), 6) << "\n";
  r.bars.push_back({modality, "original", SingleValue(raw)});
  r.bars.push_back({modality, "pre-processed", SingleValue(pre)});
  for (int z : PaperTable2().latent_dims) {
    if (!metrics.count(z)) {
      ours.push_back("-");
      continue;
    }
    const double c = metrics[z]["data_rate_kBps"][modality]["compressed"].get<double>();
    if (z <= 16) r.max_ib_16 = std::max(r.max_ib_16, c);
    r.csv << modality << ",uavsim,ib," << z << "," << Fixed(c, 6) << ","
          << Fixed(Percent(c, raw), 6) << "\n";
    ours.push_back(RateCell(c, raw));
    r.bars.push_back({modality, "IB z=" + std::to_string(z), SingleValue(c)});
  }
  r.table.push_back(ours);
}

// The paper's rates of one modality (its Tab. II).
void AddPaperRates(RateRows& r, const char* modality) {
  const PaperDataRates& paper = PaperTable2();
  const std::vector<double>& p = paper.kBps.at(modality);
  std::vector<std::string> theirs{modality, "paper", results::FormatFixed(p[0], 0),
                                  RateCell(p[1], p[0])};
  r.csv << modality << ",paper,original,," << p[0] << ",100\n";
  r.csv << modality << ",paper,preprocessed,," << p[1] << "," << Fixed(Percent(p[1], p[0]), 6)
        << "\n";
  for (std::size_t i = 0; i < paper.latent_dims.size(); ++i) {
    r.csv << modality << ",paper,ib," << paper.latent_dims[i] << "," << p[2 + i] << ","
          << Fixed(Percent(p[2 + i], p[0]), 6) << "\n";
    theirs.push_back(RateCell(p[2 + i], p[0]));
  }
  r.table.push_back(theirs);
}

void DataRateTable(Writer& w, const ReproducePlan& plan) {
  w.doc.Heading("Table II: data rates before and after pre-processing and compression");
  std::map<int, Json> metrics;
  for (int z : plan.latent_dims)
    metrics[z] = core::LoadJsonFile(
        (fs::path(w.dir) / "data_rates" / ("z" + std::to_string(z)) / "metrics.json").string());
  RateRows r;
  r.csv << "modality,source,stage,z,kBps,percent_of_original\n";
  r.table = {{"modality", "source", "original (KB/s)", "pre-processed (KB/s, %)"}};
  for (int z : PaperTable2().latent_dims)
    r.table[0].push_back("IB z=" + std::to_string(z) + " (KB/s, %)");
  for (const char* modality : kModalities) {
    try {
      AddOurRates(w, r, metrics, plan.scenario_latent_dim, modality);
    } catch (const Json::exception& e) {  // a rate missing from a run's metrics
      throw std::runtime_error((fs::path(w.dir) / "data_rates").string() + ": the runs' " +
                               "metrics.json lack " + modality + "'s data rates: " + e.what());
    }
    AddPaperRates(r, modality);
  }
  w.MeasureNumber("table2", "IB rate", "largest at z <= 16", r.max_ib_16);
  w.Csv("table2_data_rates.csv", r.csv.str());
  // The bars of our rates (a logarithmic axis: five orders of magnitude).
  WriteBars(w, "table2_data_rates_bars", "modality", "kBps", r.bars,
            "Table II: data rate per node, uavsim", "KB/s (1 KB = 1000 bytes)", true, "modality",
            "table2_data_rates.png");
  w.doc.Text(
      "One run of the scenario per z (" + core::FormatNumber(plan.rate_run_s) +
      " simulated s, nodes pre-processing, every frame's bytes counted): original = the sensor's "
      "frame as produced, pre-processed = what the node's pre-processing keeps, IB = the latent "
      "message (16-byte header + 4 z bytes of float mu; a header alone when the node found "
      "nothing). The paper's IB rates are 8 z bytes a frame (mu and sigma, no header), and its "
      "KB may be 1024 bytes; its sensors are MMAUD's, ours the scenario's. One run, no seeds: "
      "no interval.");
  w.doc.Image("table2_data_rates.png", "Table II: our data rates per stage (log scale)");
  w.doc.Table(r.table);
}

// ---------------------------------------------------------------------------
// Tab. III.

// Measures ours over the paper's count for the image and the point cloud encoder.
void FlopsTable(Writer& w) {
  w.doc.Heading("Table III: FLOPs per module");
  std::ostringstream sink;
  std::vector<FlopsRow> rows;
  BenchFlops(true, sink, &rows);
  std::ostringstream csv;
  csv << "module,ours_mflops,paper_mflops,ratio,note\n";
  std::vector<std::vector<std::string>> table{
      {"module", "ours (MFLOPs)", "paper (MFLOPs)", "ours / paper", "note"}};
  std::vector<Bar> bars;
  double image_ratio = kNaN, cloud_ratio = kNaN;
  for (const FlopsRow& r : rows) {
    std::string note = r.note;
    std::replace(note.begin(), note.end(), ',', ';');
    const double ratio = r.paper_mflops ? r.ours_mflops / *r.paper_mflops : kNaN;
    csv << r.module << "," << Fixed(r.ours_mflops, 4) << ","
        << (r.paper_mflops ? Fixed(*r.paper_mflops, 2) : "") << "," << Fixed(ratio, 4) << ","
        << note << "\n";
    table.push_back({r.module, results::FormatFixed(r.ours_mflops, 2),
                     r.paper_mflops ? results::FormatFixed(*r.paper_mflops, 2) : "-",
                     std::isfinite(ratio) ? results::FormatFixed(ratio, 3) : "-", r.note});
    std::string short_name = r.module.substr(0, r.module.find(" ("));
    std::replace(short_name.begin(), short_name.end(), ',', ';');
    bars.push_back({short_name, "uavsim", SingleValue(r.ours_mflops)});
    if (r.paper_mflops) bars.push_back({short_name, "paper", SingleValue(*r.paper_mflops)});
    if (r.module == "image encoder, paper layout") image_ratio = ratio;
    if (r.module.rfind("point cloud encoder, LiDAR", 0) == 0) cloud_ratio = ratio;
  }
  w.MeasureNumber("table3", "ours over paper", "image encoder", image_ratio);
  w.MeasureNumber("table3", "ours over paper", "point cloud encoder", cloud_ratio);
  w.Csv("table3_flops.csv", csv.str());
  WriteBars(w, "table3_flops_bars", "module", "mflops", bars,
            "Table III: MFLOPs per frame, uavsim beside the paper", "MFLOPs per frame", true,
            "module", "table3_flops.png");
  w.doc.Text(
      "`uavsim bench flops`: encoders counted from the layers' shapes at the paper's sizes (two "
      "128 x 128 crops, 1024 points, z = 16; 2 FLOPs per multiply-add), pre-processing as "
      "estimates for the default scenario's sensors.");
  w.doc.Image("table3_flops.png", "Table III: MFLOPs per module (log scale)");
  w.doc.Table(table);
}

// ---------------------------------------------------------------------------
// Fig. 15.

// Beam ("perfect", then each subset) -> SNR index -> per seed (bit/s/Hz).
using BeamRates = std::map<std::string, std::vector<Seeds>>;

// One seed's rates from its paper training's held-out estimates: in every
// window the beam steered at each subset's estimate (perfect: gain Mx My),
// averaged over the windows each beam has, into rates[beam][i][seed_index].
void AddSeedRates(const std::string& file, std::size_t seed_index, const channel::Upa& upa,
                  const Eigen::Vector3d& bs_m, double n_elements, const std::vector<double>& snr,
                  BeamRates& rates) {
  results::CsvFile est;
  const std::string error = results::ReadCsvFile(file, &est);
  if (!error.empty()) throw std::runtime_error(file + ": " + error);
  const long cm = est.Column("method"), cs = est.Column("subset");
  const long cx = est.Column("x_m"), ctx = est.Column("true_x_m");
  if (cm < 0 || cs < 0 || cx < 0 || ctx < 0) throw std::runtime_error(file + ": columns missing");
  std::map<std::string, std::vector<double>> sums;  // beam -> per snr
  std::map<std::string, std::size_t> counts;
  for (const auto& row : est.rows) {
    if (row[static_cast<std::size_t>(cm)] != "uavloc") continue;
    const auto at = [&](long c, int k) { return std::stod(row[static_cast<std::size_t>(c + k)]); };
    const Eigen::Vector3d p(at(cx, 0), at(cx, 1), at(cx, 2));
    const Eigen::Vector3d t(at(ctx, 0), at(ctx, 1), at(ctx, 2));
    // Line of sight: h = a(u_true); gamma = |h^H f|^2 with f steered at
    // the estimate (perfect: gamma = Mx My).
    const double gamma = channel::LosSteeredGain(upa, bs_m, p, t);
    const std::string& subset = row[static_cast<std::size_t>(cs)];
    for (const auto& [beam, g] : {std::pair<std::string, double>{subset, gamma},
                                  std::pair<std::string, double>{"perfect", n_elements}}) {
      if (beam == "perfect" && subset != "all") continue;
      auto& sum = sums[beam];
      sum.resize(snr.size(), 0.0);
      for (std::size_t i = 0; i < snr.size(); ++i) sum[i] += channel::RateBpsHz(snr[i], g);
      ++counts[beam];
    }
  }
  for (const auto& [beam, sum] : sums)
    for (std::size_t i = 0; i < snr.size(); ++i) rates[beam][i][seed_index] = sum[i] / counts[beam];
}

// Every beam's rate at each SNR per seed: the scenario's base station with
// a beam_upa x beam_upa array.
BeamRates RatesPerSeed(const Arms& arms, const ReproducePlan& plan, const Scenario& base,
                       const std::vector<std::string>& beams, const std::vector<double>& snr) {
  channel::BaseStationConfig bs = base.base_station;
  bs.upa.mx = bs.upa.my = plan.beam_upa;
  const channel::Upa upa = channel::Upa::FromConfig(bs);
  const double n_elements = static_cast<double>(bs.upa.mx) * bs.upa.my;
  BeamRates rates;
  for (const std::string& b : beams) rates[b].assign(snr.size(), Seeds(plan.seeds, kNaN));
  for (int seed = 1; seed <= plan.seeds; ++seed)
    AddSeedRates((fs::path(arms.ModelDir("paper", seed)) / "test_estimates.csv").string(),
                 static_cast<std::size_t>(seed - 1), upa, bs.position_m, n_elements, snr, rates);
  return rates;
}

// fig15_rate_snr.csv and its plot; returns the plot's title.
std::string PlotRates(Writer& w, const ReproducePlan& plan, const std::vector<double>& snr,
                      const std::vector<std::string>& beams, const BeamRates& rates) {
  std::ostringstream csv;
  csv << "snr_db,beam,rate_bps_hz,ci95,seeds\n";
  for (const std::string& b : beams)
    for (std::size_t i = 0; i < snr.size(); ++i) {
      const Stat s = Summarise(rates.at(b)[i]);
      csv << Fixed(snr[i], 2) << "," << b << "," << Fixed(s.mean, 6) << "," << Fixed(s.ci95, 6)
          << "," << s.n << "\n";
    }
  w.Csv("fig15_rate_snr.csv", csv.str());
  results::PlotSpec spec;
  spec.title = "Fig. 15: rate vs SNR, " + std::to_string(plan.beam_upa) + " x " +
               std::to_string(plan.beam_upa) + " UPA steered at each estimate";
  spec.x_label = "SNR (dB)";
  spec.y_label = "achievable rate (bit/s/Hz)";
  spec.x_column = "snr_db";
  spec.y_column = "rate_bps_hz";
  spec.group_column = "beam";
  spec.y_error_column = "ci95";
  spec.skip_empty_y = true;
  spec.y_min_zero = true;  // a rate is >= 0 (a few seeds' intervals reach below)
  spec.key_below = true;
  w.Warn("fig15_rate_snr.png",
         results::PlotCsv((fs::path(w.dir) / "fig15_rate_snr.csv").string(), spec));
  return spec.title;
}

// The report's table of the rates at a few SNRs.
std::vector<std::vector<std::string>> RateTable(const std::vector<double>& snr,
                                                const std::vector<std::string>& beams,
                                                const BeamRates& rates) {
  std::vector<std::vector<std::string>> table{{"beam"}};
  std::vector<std::size_t> at;
  for (double want : {0.0, 10.0, 20.0}) {
    std::size_t best = 0;
    for (std::size_t i = 0; i < snr.size(); ++i)
      if (std::abs(snr[i] - want) < std::abs(snr[best] - want)) best = i;
    at.push_back(best);
    table[0].push_back(Fixed(snr[best], 0) + " dB (bit/s/Hz)");
  }
  for (const std::string& b : beams) {
    std::vector<std::string> row{b};
    for (std::size_t i : at) row.push_back(MeanCi(Summarise(rates.at(b)[i])));
    table.push_back(row);
  }
  return table;
}

// What the claims read, per seed: each beam's mean rate over the SNR grid,
// and how far all three modalities fall below the perfect beam (%).
void MeasureRates(Writer& w, int seeds, std::size_t n_snr, const std::vector<std::string>& beams,
                  const BeamRates& rates) {
  const auto mean_rate = [&](const std::string& b) {
    Seeds out(static_cast<std::size_t>(seeds), 0.0);
    for (std::size_t s = 0; s < out.size(); ++s) {
      for (std::size_t i = 0; i < n_snr; ++i) out[s] += rates.at(b)[i][s];
      out[s] /= static_cast<double>(n_snr);
    }
    return out;
  };
  for (const std::string& b : beams) w.Measure("fig15", "mean rate", b, mean_rate(b));
  const Seeds perfect = mean_rate("perfect"), all = mean_rate("all");
  Seeds gap;
  for (std::size_t s = 0; s < perfect.size(); ++s)
    gap.push_back(100.0 * (perfect[s] - all[s]) / perfect[s]);
  w.Measure("fig15", "below perfect", "all", gap);
}

void RateFigure(Writer& w, const Arms& arms, const ReproducePlan& plan, const Scenario& base) {
  w.doc.Heading("Fig. 15: achievable rate vs SNR, the beam steered at each estimate");
  const std::vector<double> snr = channel::SnrGridDb(
      base.outputs.snr_db.from, base.outputs.snr_db.to, base.outputs.snr_db.step);
  std::vector<std::string> beams{"perfect"};
  for (const std::string& s : ModalitySubsets()) beams.push_back(s);
  const BeamRates rates = RatesPerSeed(arms, plan, base, beams, snr);
  const std::string title = PlotRates(w, plan, snr, beams, rates);
  w.doc.Text(
      "The base station of the scenario (position and boresight) with a " +
      std::to_string(plan.beam_upa) + " x " + std::to_string(plan.beam_upa) +
      " half-wavelength UPA instead of its own array (an 8 x 8 array's beam is about 12 degrees "
      "wide: errors of 0.1 m and 0.4 m then give the same curve), a line-of-sight channel at the "
      "true position and the beam steered at the paper head's estimate from each modality subset "
      "in every held-out window (`test_estimates.csv` of the paper trainings); SNR per antenna "
      "of the direct path, so the perfect beam has gain Mx My. Rates averaged over the windows "
      "each subset estimates, then over seeds.");
  w.doc.Image("fig15_rate_snr.png", title);
  w.doc.Table(RateTable(snr, beams, rates));
  MeasureRates(w, plan.seeds, snr.size(), beams, rates);
}

// ---------------------------------------------------------------------------
// Fig. 10, Tab. IV, Figs. 11-14.

void ModalityFigures(Writer& w, const Arms& arms) {
  w.doc.Heading("Fig. 10: localization error per modality combination");
  SubsetFigure(w, arms, "fig10a_modalities_preprocessed",
               "Fig. 10a: UAVLoc per modality subset, with pre-processing",
               {{"by trajectory", "paper", false}, {"by frame", "paper", true}});
  SubsetFigure(w, arms, "fig10b_modalities_raw",
               "Fig. 10b: UAVLoc per modality subset, without pre-processing",
               {{"by trajectory", "raw", false}});
}

// The four cases of Tab. IV beside the paper's RMSE (the row of its claim).
void PreprocessingTable(Writer& w, const Arms& arms) {
  w.doc.Heading("Table IV: which nodes pre-process");
  const ClaimRow& claim = PaperClaim("table4.order");
  const std::vector<std::pair<std::string, std::string>> cases = {{"no modality", "raw"},
                                                                  {"LiDAR and radar", "raw_camera"},
                                                                  {"camera", "raw_lidar_radar"},
                                                                  {"three modalities", "paper"}};
  std::ostringstream csv;
  csv << "preprocessing_applied_to,variant,rmse_m,ci95,seeds,paper_rmse_m\n";
  std::vector<std::vector<std::string>> table{
      {"pre-processing applied to", "variant", "RMSE, all modalities (m)", "paper (m)"}};
  std::vector<Bar> bars;
  for (const auto& [label, variant] : cases) {
    const double paper = claim.Paper(label);
    const Seeds v = arms.Rmse(variant, "all");
    w.Measure("table4", label, "all", v);
    const Stat s = Summarise(v);
    csv << label << "," << variant << "," << Fixed(s.mean, 6) << "," << Fixed(s.ci95, 6) << ","
        << s.n << "," << paper << "\n";
    table.push_back({label, variant, MeanCi(s), Fixed(paper, 4)});
    bars.push_back({label, "uavsim", s});
    bars.push_back({label, "paper", SingleValue(paper)});
  }
  w.Csv("table4_camera_preprocessing.csv", csv.str());
  WriteBars(w, "table4_camera_preprocessing_bars", "preprocessing_applied_to", "rmse_m", bars,
            "Table IV: RMSE by which nodes pre-process", "RMSE, all modalities (m)", true,
            "pre-processing applied to", "table4_camera_preprocessing.png");
  w.doc.Image("table4_camera_preprocessing.png",
              "Table IV: RMSE by which nodes pre-process (log scale; the paper's on MMAUD)");
  w.doc.Table(table);
}

// Figs. 11a and 11b; measures the spread over the four networks (max -
// min, all modalities) per seed, with and without pre-processing.
void TemporalFigures(Writer& w, const Arms& arms, const ReproducePlan& plan) {
  w.doc.Heading("Fig. 11: temporal networks");
  const auto t_pre = SubsetFigure(
      w, arms, "fig11a_temporal_preprocessed", "Fig. 11a: temporal networks, with pre-processing",
      {{"Mamba", "paper"}, {"GRU", "gru"}, {"LSTM", "lstm"}, {"TCN", "tcn"}});
  const auto t_raw = SubsetFigure(
      w, arms, "fig11b_temporal_raw", "Fig. 11b: temporal networks, without pre-processing",
      {{"Mamba", "raw"}, {"GRU", "raw_gru"}, {"LSTM", "raw_lstm"}, {"TCN", "raw_tcn"}});
  const std::vector<std::string> temporal = {"Mamba", "GRU", "LSTM", "TCN"};
  const auto spread = [&](const SubsetValues& v) {
    Seeds out(static_cast<std::size_t>(plan.seeds), kNaN);
    for (std::size_t s = 0; s < out.size(); ++s) {
      double lo = INFINITY, hi = -INFINITY;
      for (const std::string& t : temporal) {
        const double x = v.at(t).at("all")[s];
        lo = std::min(lo, x), hi = std::max(hi, x);
      }
      if (std::isfinite(lo) && std::isfinite(hi)) out[s] = hi - lo;
    }
    return out;
  };
  w.Measure("fig11", "spread", "pre-processed", spread(t_pre));
  w.Measure("fig11", "spread", "raw", spread(t_raw));
}

void AlignmentFigure(Writer& w, const Arms& arms) {
  w.doc.Heading("Fig. 12: time alignment");
  w.doc.Text(
      "All four trained without random modality dropout, as the paper says for this "
      "comparison (TE-Align here is the `te_align` variant, not the default `paper` model).");
  SubsetFigure(w, arms, "fig12_alignment", "Fig. 12: time alignment",
               {{"TE-Align", "te_align"},
                {"first", "resample_first"},
                {"middle", "resample_middle"},
                {"random", "resample_random"}});
}

// Fig. 13; measures the gain of both modules over neither, averaged over
// the subsets with radar and over those without, per seed.
void FusionModuleFigure(Writer& w, const Arms& arms, const ReproducePlan& plan) {
  w.doc.Heading("Fig. 13: MADW and MICA");
  const auto fusion = SubsetFigure(w, arms, "fig13_fusion_modules", "Fig. 13: fusion modules",
                                   {{"MADW + MICA", "paper"},
                                    {"MADW", "no_mica"},
                                    {"MICA", "no_madw"},
                                    {"neither", "no_madw_mica"}});
  Seeds with(static_cast<std::size_t>(plan.seeds), 0.0), without = with;
  for (std::size_t s = 0; s < with.size(); ++s) {
    int nw = 0, nwo = 0;
    for (const std::string& sub : ModalitySubsets()) {
      const double gain = fusion.at("neither").at(sub)[s] - fusion.at("MADW + MICA").at(sub)[s];
      if (sub.find("radar") != std::string::npos)
        with[s] += gain, ++nw;
      else
        without[s] += gain, ++nwo;
    }
    with[s] /= nw, without[s] /= nwo;
  }
  w.Measure("fig13", "gain of both over neither", "with radar", with);
  w.Measure("fig13", "gain of both over neither", "without radar", without);
}

void BaselineFigure(Writer& w, const Arms& arms) {
  w.doc.Heading("Fig. 14: fusion baselines");
  SubsetFigure(w, arms, "fig14_fusion_baselines", "Fig. 14: UAVLoc vs multimodal fusion baselines",
               {{"UAVLoc", "paper"},
                {"early fusion", "early_fusion"},
                {"late weighted fusion", "late_fusion"},
                {"modality dropout", "modality_dropout"},
                {"HeMIS", "hemis"}});
}

// ---------------------------------------------------------------------------
// The report's opening.

// The wall time (s) over every invocation in DIR/invocations.csv (those
// that got past the episodes), counted into *invocations.
double InvocationsWallS(const std::string& dir, std::size_t* invocations) {
  double total_wall_s = 0.0;
  results::CsvFile log;
  if (results::ReadCsvFile((fs::path(dir) / "invocations.csv").string(), &log).empty()) {
    const long c = log.Column("wall_s");
    for (const auto& row : log.rows)
      if (c >= 0) total_wall_s += std::stod(row[static_cast<std::size_t>(c)]), ++*invocations;
  }
  return total_wall_s;
}

// The scenario, the protocol and the trainings; returns the protocol's
// block (WriteVerdicts ends it with the verdicts' rules).
// trainings.csv (every stage's epochs, best epoch, cap and patience) and a
// sentence saying how many stages reached their validation plateau within
// the plan's one budget (issue 41: a training stopped by its cap has not
// learnt what its data allow).
void BudgetRecord(Writer& w, const ReproducePlan& plan, const Arms& arms) {
  std::ostringstream csv;
  csv << "model,stage,epochs,best_epoch,max_epochs,patience,plateau\n";
  std::size_t reached = 0, stage1 = 0, stage1_reached = 0;
  const std::vector<Arms::StageBudget> budgets = arms.Budgets();
  for (const Arms::StageBudget& b : budgets) {
    csv << b.id << "," << b.stage << "," << b.epochs << "," << b.best_epoch << "," << b.max_epochs
        << "," << b.patience << "," << (b.plateau() ? "yes" : "no") << "\n";
    reached += b.plateau();
    stage1 += b.stage1;
    stage1_reached += b.stage1 && b.plateau();
  }
  w.Csv("trainings.csv", csv.str());
  const pipeline::TrainingConfig& t = plan.training;
  w.doc.Text("Budget, one for the paper's design and every baseline: stage 1 at most " +
             std::to_string(t.stage1_max_epochs) + " epochs (patience " +
             std::to_string(t.stage1_patience) + ") of at most " +
             std::to_string(t.stage1_max_samples_per_epoch) + " observations, stage 2 at most " +
             std::to_string(t.stage2_max_epochs) + " epochs (patience " +
             std::to_string(t.stage2_patience) + "). " + std::to_string(reached) + " of " +
             std::to_string(budgets.size()) +
             " training stages reached their validation plateau (patience epochs without a "
             "better validation loss when they stopped; stage 1: " +
             std::to_string(stage1_reached) + " of " + std::to_string(stage1) +
             "); the others stopped at the cap before their patience ran out (trainings.csv).");
}

std::size_t Introduction(Writer& w, const ReproduceReportInputs& in, const Arms& arms) {
  const ReproducePlan& plan = *in.plan;
  Document& doc = w.doc;
  doc.Text("Scenario `" + in.scenario->name + "`" +
           (in.quick ? " at toy size (`--quick`: its numbers "
                       "say nothing about the paper; the full "
                       "plan does)"
                     : "") +
           "; uavsim " + Version() + " (" + GitHash() + "). Command: `" + in.command_line + "`.");
  const std::size_t protocol_at = doc.blocks.size();
  doc.Text(
      "Protocol: " + std::to_string(plan.episodes.episodes) + " simulated flights of " +
      core::FormatNumber(plan.episodes.episode_s) +
      " s per episode set (the same flights, weather and uplink loss in every set; sets differ "
      "in what the nodes pre-process), split by trajectory 70/15/15 (held-out flights; Fig. "
      "10a also by frame, the split common in the literature, as a second column); " +
      std::to_string(plan.seeds) +
      " training seeds (each its own split, initial weights and dropout); every value is the "
      "mean over seeds with its 95 % confidence interval (Student t).");
  std::size_t invocations = 0;
  const double total_wall_s = InvocationsWallS(in.dir, &invocations);
  doc.Text("Trainings: " + std::to_string(arms.count()) + " (" + std::to_string(in.trained_now) +
           " by this invocation), " +
           core::FormatNumber(std::round(arms.TrainingSeconds() / 60.0)) +
           " CPU-minutes in the training stages; wall time " +
           core::FormatNumber(std::round(total_wall_s / 6.0) / 10.0) + " min over " +
           std::to_string(invocations) +
           " invocation(s), each in invocations.csv (an invocation stopped before its trainings "
           "began has no row there; one killed counts to its last finished training).");
  BudgetRecord(w, plan, arms);
  return protocol_at;
}

}  // namespace

std::vector<std::string> WriteReproduceReport(const ReproduceReportInputs& in) {
  const ReproducePlan& plan = *in.plan;
  const Arms arms(in.dir, plan);
  Writer w;
  w.dir = in.dir;
  w.measured.latent_dims = plan.latent_dims;
  w.measured.z0 = plan.scenario_latent_dim;
  const std::size_t protocol_at = Introduction(w, in, arms);
  const std::size_t summary_at = w.doc.blocks.size();

  // The artefacts, each measuring what its claims read.
  DecoderFigures(w, arms, plan);
  DataRateTable(w, plan);
  FlopsTable(w);
  ModalityFigures(w, arms);
  PreprocessingTable(w, arms);
  TemporalFigures(w, arms, plan);
  AlignmentFigure(w, arms);
  FusionModuleFigure(w, arms, plan);
  BaselineFigure(w, arms);
  RateFigure(w, arms, plan, *in.scenario);

  // The claims: a row of the paper's table each, in its order.
  std::vector<Claim> claims;
  for (const ClaimRow& row : PaperClaims()) claims.push_back(MakeClaim(row, w.measured));
  const std::string title = "The paper's Sec. VI in simulation: " + in.scenario->name +
                            (in.quick ? " (quick, toy size)" : "");
  WriteVerdicts(in.dir, plan.equivalence_fraction, kRecordedRule, claims, w.doc, protocol_at,
                summary_at, title);
  return w.warnings;
}

}  // namespace uavsim::sim
