// The paper's Sec. VI claims, one row each, in the report's order; the
// rows' fields and the texts' {…} are explained in
// apps/reproduce/reproduce_claim_table.h.
//
// What the artefacts measure (apps/reproduce/reproduce_report.cpp), as
// table / series / category, per seed:
//   fig07 fig08 fig09 / IB, MLP, IB without pre-processing, IB on target,
//       centroid on target / each latent size z
//   fig10a / by trajectory, by frame / subset     fig10b / by trajectory / subset
//   fig11a fig11b / Mamba, GRU, LSTM, TCN / subset
//   fig11 / spread (max - min over the four, all modalities) / pre-processed, raw
//   fig12 / TE-Align, first, middle, random / subset
//   fig13 / MADW + MICA, MADW, MICA, neither / subset
//   fig13 / gain of both over neither (mean over subsets) / with radar, without radar
//   fig14 / UAVLoc, early fusion, late weighted fusion, modality dropout, HeMIS / subset
//   table4 / no modality, LiDAR and radar, camera, three modalities / all
//   fig15 / mean rate / perfect, each subset     fig15 / below perfect / all
// and as single numbers:
//   table2 / pre-processed share (% of the original) / camera, lidar, radar
//   table2 / IB rate (KB/s) / largest at z <= 16
//   table3 / ours over paper / image encoder, point cloud encoder
#include "apps/reproduce/reproduce_claim_table.h"

// GCC 12's -Wmaybe-uninitialized misreads the destruction, at the end of
// static initialisation, of the table's brace-initialised temporaries (the
// empty ClaimCriterion::values of rows without a criterion): a false
// positive of that warning on large aggregate initialisers, silenced here.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace uavsim::sim {
namespace {

using P = ComparisonPattern;
using K = ClaimCriterion;
constexpr ClaimRange kOnce = ClaimRange::kOnce;
constexpr ClaimRange kEverySubset = ClaimRange::kEverySubset;
constexpr ClaimRange kEveryZ = ClaimRange::kEveryLatentSize;
constexpr ClaimRange kSmallZ = ClaimRange::kSmallLatentSize;
constexpr ClaimRange kSubsetPairs = ClaimRange::kSubsetPairs;

// A table, not a function: the rows are data.
const std::vector<ClaimRow> kRows = {
    // Figs. 7-9: each node's decoder alone vs latent size z.
    {"fig07.preprocessing",
     "Fig. 7",
     "Pre-processing lowers the camera error at every latent size (\"the scheme with included "
     "preprocessing consistently outperforms\")",
     ClaimRow::kAllHold,
     {{"pre-processed below raw; z {z}", "fig07/IB/{z}", "fig07/IB without pre-processing/{z}",
       kEveryZ}},
     {},
     "z {z0}: {fig07/IB/{z0}} m pre-processed vs {fig07/IB without pre-processing/{z0}} m raw"},
    {"fig07.ib_vs_mlp",
     "Fig. 7",
     "IB-based compression is superior to the MLP (camera, every z)",
     ClaimRow::kAllHold,
     {{"IB below MLP; z {z}", "fig07/IB/{z}", "fig07/MLP/{z}", kEveryZ}},
     {},
     "z {zlo}: IB {fig07/IB/{zlo}} m, MLP {fig07/MLP/{zlo}} m"},
    {"fig07.mlp_vs_z",
     "Fig. 7",
     "With the MLP, the camera error decreases as z grows",
     ClaimRow::kAllHold,
     {{"MLP z {zhi} below z {zlo}", "fig07/MLP/{zhi}", "fig07/MLP/{zlo}"}},
     {},
     "z {zlo}: {fig07/MLP/{zlo}} m, z {zhi}: {fig07/MLP/{zhi}} m"},
    {"fig08.preprocessing",
     "Fig. 8",
     "Pre-processing lowers the lidar error at every latent size (\"the scheme with included "
     "preprocessing consistently outperforms\")",
     ClaimRow::kAllHold,
     {{"pre-processed below raw; z {z}", "fig08/IB/{z}", "fig08/IB without pre-processing/{z}",
       kEveryZ}},
     {},
     "z {z0}: {fig08/IB/{z0}} m pre-processed vs {fig08/IB without pre-processing/{z0}} m raw"},
    {"fig08.ib_vs_mlp",
     "Fig. 8",
     "IB outperforms the MLP at low-dimensional latent spaces (lidar)",
     ClaimRow::kAllHold,
     {{"IB below MLP; z {z}", "fig08/IB/{z}", "fig08/MLP/{z}", kSmallZ}},
     {},
     "z {zlo}: IB {fig08/IB/{zlo}} m, MLP {fig08/MLP/{zlo}} m"},
    {"fig09.preprocessing",
     "Fig. 9",
     "Pre-processing lowers the radar error at every latent size (\"the scheme with included "
     "preprocessing consistently outperforms\")",
     ClaimRow::kAllHold,
     {{"pre-processed below raw; z {z}", "fig09/IB/{z}", "fig09/IB without pre-processing/{z}",
       kEveryZ}},
     {},
     "z {z0}: {fig09/IB/{z0}} m pre-processed vs {fig09/IB without pre-processing/{z0}} m raw"},
    {"fig09.ib_vs_mlp",
     "Fig. 9",
     "IB outperforms the MLP at low-dimensional latent spaces (radar)",
     ClaimRow::kAllHold,
     {{"IB below MLP; z {z}", "fig09/IB/{z}", "fig09/MLP/{z}", kSmallZ}},
     {},
     "z {zlo}: IB {fig09/IB/{zlo}} m, MLP {fig09/MLP/{zlo}} m"},

    // Table II: data rates (shares of the original in %, rates in KB/s).
    {"table2.camera_radar_share",
     "Table II",
     "Pre-processing reduces the camera and radar data rates to 20-30 % of the original",
     ClaimRow::kCriterion,
     {},
     {K::kSharesInRange,
      {"table2/pre-processed share/camera", "table2/pre-processed share/radar"},
      20.0,
      30.0,
      "both within 20-30 %",
      "both reduced, not to 20-30 % (the sensors differ from MMAUD's)",
      "not reduced"},
     "camera {table2/pre-processed share/camera:3} %, radar "
     "{table2/pre-processed share/radar:3} %"},
    {"table2.lidar_share",
     "Table II",
     "LiDAR pre-processing attains much larger reductions (0.39 %) than the camera's and "
     "radar's",
     ClaimRow::kCriterion,
     {},
     {K::kFirstBelowRest,
      {"table2/pre-processed share/lidar", "table2/pre-processed share/camera",
       "table2/pre-processed share/radar"},
      0.0,
      0.0,
      "criterion: LiDAR's share below the camera's and the radar's"},
     "LiDAR {table2/pre-processed share/lidar:4} %"},
    {"table2.ib_rate",
     "Table II",
     "IB compression brings every modality down to a few KB/s",
     ClaimRow::kCriterion,
     {},
     {K::kAtMost,
      {"table2/IB rate/largest at z <= 16"},
      0.0,
      10.0,
      "criterion: every modality at most 10 KB/s for z <= 16"},
     "at most {table2/IB rate/largest at z <= 16:3} KB/s for z <= 16"},

    // Table III: FLOPs (ours over the paper's count).
    {"table3.image_encoder",
     "Table III",
     "The image encoder costs 147.32 MFLOPs",
     ClaimRow::kCriterion,
     {},
     {K::kRatioNearOne,
      {"table3/ours over paper/image encoder"},
      0.0,
      0.01,
      "criterion: within 1 % of the paper's count"},
     "ratio {table3/ours over paper/image encoder:4}"},
    {"table3.cloud_encoder",
     "Table III",
     "The point cloud encoder costs 1426.98 MFLOPs",
     ClaimRow::kCriterion,
     {},
     {K::kRatioNearOne,
      {"table3/ours over paper/point cloud encoder"},
      0.0,
      0.01,
      "criterion: within 1 % of the paper's count (Table I's PointNet gives 302.5 M)"},
     "ratio {table3/ours over paper/point cloud encoder:3} (LiDAR, 4 channels)"},

    // Fig. 10 and Sec. VII: modality subsets (series "by trajectory", "by frame").
    {"fig10a.more_modalities",
     "Fig. 10a",
     "Localization improves with the number of modalities (with pre-processing)",
     ClaimRow::kAllHold,
     {{"{more} below {fewer}", "fig10a/by trajectory/{more}", "fig10a/by trajectory/{fewer}",
       kSubsetPairs},
      {"{more} below {fewer}", "fig10a/by frame/{more}", "fig10a/by frame/{fewer}", kSubsetPairs,
       P::kLowerBetter, P::kByFrame}},
     {},
     "all {fig10a/by trajectory/all} m; camera {fig10a/by trajectory/camera}, lidar "
     "{fig10a/by trajectory/lidar}, radar {fig10a/by trajectory/radar} m",
     "(all {fig10a/by frame/all} m)"},
    {"fig10b.more_modalities",
     "Fig. 10b",
     "Localization improves with the number of modalities (without pre-processing)",
     ClaimRow::kAllHold,
     {{"{more} below {fewer}", "fig10b/by trajectory/{more}", "fig10b/by trajectory/{fewer}",
       kSubsetPairs}},
     {},
     "all {fig10b/by trajectory/all} m"},
    {"fig10.preprocessing",
     "Figs. 10a, 10b",
     "Pre-processing has a strong positive influence on accuracy (every modality combination)",
     ClaimRow::kAllHold,
     {{"pre-processed below raw; {subset}", "fig10a/by trajectory/{subset}",
       "fig10b/by trajectory/{subset}", kEverySubset}},
     {},
     "all: {fig10a/by trajectory/all} vs {fig10b/by trajectory/all} m"},
    {"sec7.camera_best",
     "Sec. VII",
     "In good visibility the camera performs best, and LiDAR outperforms radar",
     ClaimRow::kAllHold,
     {{"camera below lidar", "fig10a/by trajectory/camera", "fig10a/by trajectory/lidar"},
      {"camera below radar", "fig10a/by trajectory/camera", "fig10a/by trajectory/radar"},
      {"lidar below radar", "fig10a/by trajectory/lidar", "fig10a/by trajectory/radar"}},
     {},
     "camera {fig10a/by trajectory/camera}, lidar {fig10a/by trajectory/lidar}, radar "
     "{fig10a/by trajectory/radar} m (all weathers of the set)"},

    // Table IV: which nodes pre-process (RMSE on all modalities, m).
    {"table4.order",
     "Table IV",
     "RMSE falls in the order: no pre-processing, LiDAR and radar only, camera only, all three "
     "(0.372 > 0.095 > 0.035 > 0.022 m)",
     ClaimRow::kAllHold,
     {{"LiDAR and radar below none", "table4/LiDAR and radar/all", "table4/no modality/all"},
      {"camera below LiDAR and radar", "table4/camera/all", "table4/LiDAR and radar/all"},
      {"three below camera", "table4/three modalities/all", "table4/camera/all"}},
     {},
     "{table4/no modality/all} / {table4/LiDAR and radar/all} / {table4/camera/all} / "
     "{table4/three modalities/all} m",
     "",
     {{"no modality", 0.3718},
      {"LiDAR and radar", 0.0952},
      {"camera", 0.0347},
      {"three modalities", 0.0223}}},

    // Fig. 11: temporal networks (fig11: the spread over them, max - min per seed).
    {"fig11a.mamba_best",
     "Fig. 11a",
     "Mamba achieves the lowest RMSE when all three modalities are available",
     ClaimRow::kAllHold,
     {{"Mamba below GRU", "fig11a/Mamba/all", "fig11a/GRU/all"},
      {"Mamba below LSTM", "fig11a/Mamba/all", "fig11a/LSTM/all"},
      {"Mamba below TCN", "fig11a/Mamba/all", "fig11a/TCN/all"}},
     {},
     "Mamba {fig11a/Mamba/all}, GRU {fig11a/GRU/all}, LSTM {fig11a/LSTM/all}, TCN "
     "{fig11a/TCN/all} m"},
    {"fig11b.raw_worse",
     "Fig. 11b",
     "Raw data increases every temporal network's error significantly",
     ClaimRow::kAllHold,
     {{"Mamba: pre-processed below raw", "fig11a/Mamba/all", "fig11b/Mamba/all"},
      {"GRU: pre-processed below raw", "fig11a/GRU/all", "fig11b/GRU/all"},
      {"LSTM: pre-processed below raw", "fig11a/LSTM/all", "fig11b/LSTM/all"},
      {"TCN: pre-processed below raw", "fig11a/TCN/all", "fig11b/TCN/all"}},
     {},
     "all modalities, raw: Mamba {fig11b/Mamba/all}, GRU {fig11b/GRU/all} m"},
    {"fig11b.spread",
     "Fig. 11b",
     "Without pre-processing the temporal networks' differences shrink",
     ClaimRow::kAllHold,
     {{"spread raw below spread pre-processed", "fig11/spread/raw", "fig11/spread/pre-processed"}},
     {},
     "spread (max - min, all modalities): pre-processed {fig11/spread/pre-processed} m, raw "
     "{fig11/spread/raw} m"},

    // Figs. 12-14: alignment, fusion modules, fusion baselines.
    {"fig12.te_align",
     "Fig. 12",
     "TE-Align consistently outperforms the resampling methods",
     ClaimRow::kAllHold,
     {{"TE-Align below first; {subset}", "fig12/TE-Align/{subset}", "fig12/first/{subset}",
       kEverySubset},
      {"TE-Align below middle; {subset}", "fig12/TE-Align/{subset}", "fig12/middle/{subset}",
       kEverySubset},
      {"TE-Align below random; {subset}", "fig12/TE-Align/{subset}", "fig12/random/{subset}",
       kEverySubset}},
     {},
     "all modalities: TE-Align {fig12/TE-Align/all}, first {fig12/first/all}, middle "
     "{fig12/middle/all}, random {fig12/random/all} m"},
    {"fig13.both_modules",
     "Fig. 13",
     "In most cases the best performance is with both MADW and MICA",
     ClaimRow::kMostHold,
     {{"both below MADW; {subset}", "fig13/MADW + MICA/{subset}", "fig13/MADW/{subset}",
       kEverySubset},
      {"both below MICA; {subset}", "fig13/MADW + MICA/{subset}", "fig13/MICA/{subset}",
       kEverySubset},
      {"both below neither; {subset}", "fig13/MADW + MICA/{subset}", "fig13/neither/{subset}",
       kEverySubset}},
     {},
     "all modalities: both {fig13/MADW + MICA/all}, MADW {fig13/MADW/all}, MICA "
     "{fig13/MICA/all}, neither {fig13/neither/all} m"},
    {"fig13.radar_gain",
     "Fig. 13",
     "The improvement is particularly evident for combinations involving radar",
     ClaimRow::kAllHold,
     {{"gain with radar above gain without", "fig13/gain of both over neither/with radar",
       "fig13/gain of both over neither/without radar", kOnce, P::kHigherBetter}},
     {},
     "gain of both over neither: subsets with radar "
     "{fig13/gain of both over neither/with radar} m, without "
     "{fig13/gain of both over neither/without radar} m"},
    {"fig14.uavloc_best",
     "Fig. 14",
     "UAVLoc outperforms all the considered baselines",
     ClaimRow::kAllHold,
     {{"UAVLoc below early fusion; {subset}", "fig14/UAVLoc/{subset}",
       "fig14/early fusion/{subset}", kEverySubset},
      {"UAVLoc below late weighted fusion; {subset}", "fig14/UAVLoc/{subset}",
       "fig14/late weighted fusion/{subset}", kEverySubset},
      {"UAVLoc below modality dropout; {subset}", "fig14/UAVLoc/{subset}",
       "fig14/modality dropout/{subset}", kEverySubset},
      {"UAVLoc below HeMIS; {subset}", "fig14/UAVLoc/{subset}", "fig14/HeMIS/{subset}",
       kEverySubset}},
     {},
     "all modalities: UAVLoc {fig14/UAVLoc/all}, early {fig14/early fusion/all}, late "
     "{fig14/late weighted fusion/all}, dropout {fig14/modality dropout/all}, HeMIS "
     "{fig14/HeMIS/all} m"},

    // Fig. 15: the rate of the beam steered at each estimate (bit/s/Hz, the mean over the
    // SNR grid; "below perfect": how far all three fall below the perfect beam, in %).
    {"fig15.fusion_rate",
     "Fig. 15",
     "Multimodal fusion improves the achievable rate over single modalities",
     ClaimRow::kAllHold,
     {{"all above camera", "fig15/mean rate/all", "fig15/mean rate/camera", kOnce,
       P::kHigherBetter},
      {"all above lidar", "fig15/mean rate/all", "fig15/mean rate/lidar", kOnce, P::kHigherBetter},
      {"all above radar", "fig15/mean rate/all", "fig15/mean rate/radar", kOnce, P::kHigherBetter}},
     {},
     "mean rate over the grid: all {fig15/mean rate/all:3}, camera {fig15/mean rate/camera:3}, "
     "lidar {fig15/mean rate/lidar:3}, radar {fig15/mean rate/radar:3} bit/s/Hz"},
    {"fig15.near_perfect",
     "Fig. 15",
     "With all three modalities the rate approaches the rate at the known position",
     ClaimRow::kCriterion,
     {},
     {K::kIntervalBelow,
      {"fig15/below perfect/all"},
      0.0,
      5.0,
      "criterion: \"approaches\" read as within 5 % (the interval's upper end)"},
     "all three {fig15/below perfect/all} % below the perfect beam (mean over the grid)"},
};

}  // namespace

const std::vector<ClaimRow>& PaperClaims() { return kRows; }

const PaperDataRates& PaperTable2() {
  static const PaperDataRates rates = {{4, 8, 16, 32, 64},
                                       {{"camera", {63701, 13261, 0.94, 1.88, 3.75, 7.50, 15.00}},
                                        {"lidar", {4685, 1.87, 0.31, 0.63, 1.25, 2.50, 5.00}},
                                        {"radar", {111, 31.74, 0.47, 0.94, 1.88, 3.75, 7.50}}}};
  return rates;
}

}  // namespace uavsim::sim
