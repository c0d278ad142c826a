// Which temporal regressor the edge network runs (temporal_regressor.h): the
// paper's Mamba or one of the baselines it is compared against in Sec. VI
// (Fig. 11). Torch-free, for configuration code.
#pragma once

#include <utility>
#include <vector>

namespace uavsim::pipeline {

enum class TemporalKind { kMamba, kGru, kLstm, kTcn };

// The names in configuration files: "mamba", "gru", "lstm", "tcn".
inline const std::vector<std::pair<const char*, TemporalKind>>& TemporalKindNames() {
  static const std::vector<std::pair<const char*, TemporalKind>> names = {
      {"mamba", TemporalKind::kMamba},
      {"gru", TemporalKind::kGru},
      {"lstm", TemporalKind::kLstm},
      {"tcn", TemporalKind::kTcn}};
  return names;
}

inline const char* TemporalKindName(TemporalKind kind) {
  for (const auto& [name, value] : TemporalKindNames())
    if (value == kind) return name;
  return "?";
}

}  // namespace uavsim::pipeline
