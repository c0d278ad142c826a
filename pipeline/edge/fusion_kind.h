// How the edge network fuses a window's aligned modalities before the
// temporal regressor (uavloc_model.h): the paper's MADW + MICA + concatenation
// or one of the fusion baselines it is compared against in Sec. VI (Fig. 14),
// built from the paper's description of each. Torch-free, for configuration
// code.
#pragma once

#include <utility>
#include <vector>

namespace uavsim::pipeline {

enum class FusionKind {
  kUavLoc,  // MADW -> MICA -> [t^{c,f}, t^{l,f}, t^{r,f}] (Eqs. (21)-(26)), each switchable
  kEarly,   // feature-level early fusion: each modality projected to a shared
            // space (Linear z -> z, ReLU; zero when missing), concatenated
  kLate,    // late weighted fusion: a temporal regressor and head per
            // modality on its own latent, the positions weighed by a
            // softmax of learnable weights over the modalities available
  kHemis,   // HeMIS-style: each modality embedded (Linear z -> 3z/2, ReLU),
            // the mean and variance over the available embeddings
};

// The names in configuration files: "uavloc", "early", "late", "hemis".
inline const std::vector<std::pair<const char*, FusionKind>>& FusionKindNames() {
  static const std::vector<std::pair<const char*, FusionKind>> names = {
      {"uavloc", FusionKind::kUavLoc},
      {"early", FusionKind::kEarly},
      {"late", FusionKind::kLate},
      {"hemis", FusionKind::kHemis}};
  return names;
}

// HeMIS's embedding width for latent size z: 3z/2, so that [mean, variance]
// is as wide as the paper's concatenation of three modalities (3z).
inline int HemisEmbedding(int latent_dim) { return 3 * latent_dim / 2; }

inline const char* FusionKindName(FusionKind kind) {
  for (const auto& [name, value] : FusionKindNames())
    if (value == kind) return name;
  return "?";
}

}  // namespace uavsim::pipeline
