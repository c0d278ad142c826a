#include "pipeline/variants.h"

namespace uavsim::pipeline {

const std::vector<Variant>& Variants() {
  // The paper trains the alignment comparison without random modality
  // dropout (Sec. VI, Fig. 12), and describes modality dropout as early
  // fusion trained with it (Fig. 14): those variants set both dropouts.
  static const std::vector<Variant> variants = {
      {"paper", "every figure", "UAVLoc as the paper designs it, method uavloc", "{}", false, 0},
      {"gru", "Fig. 11", "a GRU in the Mamba's place, as many parameters", R"({"temporal": "gru"})",
       false, 0},
      {"lstm", "Fig. 11", "an LSTM in the Mamba's place, as many parameters",
       R"({"temporal": "lstm"})", false, 0},
      {"tcn", "Fig. 11", "a dilated causal TCN in the Mamba's place", R"({"temporal": "tcn"})",
       false, 0},
      {"te_align", "Fig. 12", "UAVLoc without modality dropout (resamplers' reference)",
       R"({"modality_dropout": 0, "window_dropout": 0})", false, 0},
      {"resample_first", "Fig. 12", "each modality's first frame in the window",
       R"({"alignment": "first", "modality_dropout": 0, "window_dropout": 0})", false, 0},
      {"resample_middle", "Fig. 12", "each modality's middle frame in the window",
       R"({"alignment": "middle", "modality_dropout": 0, "window_dropout": 0})", false, 0},
      {"resample_random", "Fig. 12", "a random frame of each modality in the window",
       R"({"alignment": "random", "modality_dropout": 0, "window_dropout": 0})", false, 0},
      {"no_madw", "Fig. 13", "UAVLoc without MADW", R"({"madw": false})", false, 0},
      {"no_mica", "Fig. 13", "UAVLoc without MICA", R"({"mica": false})", false, 0},
      {"no_madw_mica", "Fig. 13", "UAVLoc without MADW and MICA",
       R"({"madw": false, "mica": false})", false, 0},
      {"early_fusion", "Fig. 14", "early fusion, trained without modality dropout",
       R"({"fusion": "early", "modality_dropout": 0, "window_dropout": 0})", false, 0},
      {"late_fusion", "Fig. 14", "late weighted fusion of per-modality branches",
       R"({"fusion": "late"})", false, 0},
      {"modality_dropout", "Fig. 14", "early fusion trained with modality dropout",
       R"({"fusion": "early"})", false, 0},
      {"hemis", "Fig. 14", "HeMIS: mean and variance of available embeddings",
       R"({"fusion": "hemis"})", false, 0},
      {"mlp_bottleneck", "Figs. 7-9, Tab. II", "nodes compress with an MLP, not the IB head", "{}",
       true, 0},
      {"raw", "Figs. 7-10, Tab. II, IV", "nodes encode raw data, no pre-processing", "{}", false,
       7},
      {"raw_camera", "Tab. IV", "the camera raw; LiDAR and radar pre-processed", "{}", false, 1},
      {"raw_lidar_radar", "Tab. IV", "LiDAR and radar raw; the camera pre-processed", "{}", false,
       6},
      {"raw_gru", "Fig. 11b", "gru on nodes that encode raw data", R"({"temporal": "gru"})", false,
       7},
      {"raw_lstm", "Fig. 11b", "lstm on nodes that encode raw data", R"({"temporal": "lstm"})",
       false, 7},
      {"raw_tcn", "Fig. 11b", "tcn on nodes that encode raw data", R"({"temporal": "tcn"})", false,
       7},
  };
  return variants;
}

const Variant* FindVariant(const std::string& name) {
  for (const Variant& v : Variants())
    if (name == v.name) return &v;
  return nullptr;
}

std::string VariantNames() {
  std::string names;
  for (const Variant& v : Variants()) names += (names.empty() ? "" : ", ") + std::string(v.name);
  return names;
}

bool SameNodes(const Variant& a, const Variant& b) {
  return a.mlp_bottleneck == b.mlp_bottleneck && a.raw_modalities == b.raw_modalities;
}

std::string VariantMethod(const std::string& name) { return name == "paper" ? "uavloc" : name; }

TrainingConfig ApplyVariant(const Variant& v, const TrainingConfig& base) {
  return TrainingConfigFromJson(core::Json::parse(v.config), std::string("variant ") + v.name,
                                base);
}

}  // namespace uavsim::pipeline
