// The three sensing modalities and their names ("camera", "lidar", "radar":
// the keys of metrics.json and of SensorConfig::modality()). Shared by the
// channel's packets and the pipeline's observations.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace uavsim::core {

enum class Modality : std::uint8_t { kCamera = 0, kLidar = 1, kRadar = 2 };
constexpr int kModalityCount = 3;

constexpr const char* ModalityName(Modality m) {
  switch (m) {
    case Modality::kCamera:
      return "camera";
    case Modality::kLidar:
      return "lidar";
    case Modality::kRadar:
      return "radar";
  }
  return "unknown";
}

// The inverse of ModalityName; nullopt for any other name.
inline std::optional<Modality> ModalityFromName(std::string_view name) {
  for (int i = 0; i < kModalityCount; ++i) {
    const auto m = static_cast<Modality>(i);
    if (name == ModalityName(m)) return m;
  }
  return std::nullopt;
}

}  // namespace uavsim::core
