#include "sim/node_content.h"

#include <stdexcept>

namespace uavsim::sim {

const NodeContent& ContentOf(const channel::Message& m) {
  const auto* content = dynamic_cast<const NodeContent*>(m.content.get());
  if (!content) throw std::logic_error("a message without a sensing node's content");
  return *content;
}

bool NodeObservation::Found() const {
  return (camera && camera->detected) || (points && points->count() > 0);
}

std::uint64_t NodeObservation::PreprocessedBytes() const {
  if (!Found()) return 0;  // nothing to send
  if (camera)
    return 2ull * pipeline::CameraObservation::kCropPx * pipeline::CameraObservation::kCropPx + 64;
  if (points) return 4ull * points->values.size();
  return 0;
}

std::uint64_t NodeContent::PreprocessedBytes() const {
  std::uint64_t bytes = NodeObservation::PreprocessedBytes();
  for (const NodeObservation& o : further) bytes += o.PreprocessedBytes();
  return bytes;
}

}  // namespace uavsim::sim
