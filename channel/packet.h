// What a sensing node sends to the edge server: one Message per frame, and how
// the link cuts it into fragments no larger than the MTU.
//
// Message size until the learned pipeline lands: a node sends its IB latent,
// latent_dim float32 values, behind a kMessageHeaderBytes application header
// (LatentMessageBytes). The header is
//   node index u16 | modality u8 | flags u8 | sequence u32 | t_capture_ns i64
// = 16 bytes; it is counted, never serialized.
//
// Fragmentation: with fragment payload P = mtu_bytes - fragment_header_bytes, a
// message of B >= 1 bytes becomes n = ceil(B / P) fragments; fragments 0..n-2
// carry P bytes and the last carries B - (n - 1) P; each fragment adds
// fragment_header_bytes on the wire. A message is delivered only if all its
// fragments are.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/modality.h"
#include "core/time.h"

namespace uavsim::channel {

using core::kModalityCount;
using core::Modality;
using core::ModalityFromName;
using core::ModalityName;

// What a message carries for the edge besides its latent (the node's
// pre-processed measurement): opaque to the channel, which only moves it.
// The engine's sensing node defines the one kind (sim/sensing_node.h:
// NodeContent, read back with ContentOf).
struct MessageContent {
  virtual ~MessageContent() = default;
};

struct Message {
  std::uint32_t node = 0;  // the sender's index in the scenario's node list
  Modality modality = Modality::kCamera;
  std::uint64_t sequence = 0;       // per node, 0, 1, 2, ... in capture order
  core::SimTime t_capture_ns = 0;   // when the frame was captured
  std::uint32_t payload_bytes = 0;  // application bytes (header included), >= 1
  std::vector<float> latent;        // the IB latent; empty until the encoder lands
  // What else the node sent (its pre-processed measurement for the edge's
  // classical filter); payload_bytes counts it.
  std::shared_ptr<const MessageContent> content;
};

constexpr std::uint32_t kMessageHeaderBytes = 16;

// Bytes of a message carrying a latent of latent_dim float32 values.
constexpr std::uint32_t LatentMessageBytes(int latent_dim) {
  return kMessageHeaderBytes + 4u * static_cast<std::uint32_t>(latent_dim);
}

// How a message of payload_bytes travels (see the header comment). Requires
// payload_bytes >= 1 and fragment_header_bytes < mtu_bytes.
struct Fragmentation {
  std::uint32_t count = 0;            // n
  std::uint32_t full_wire_bytes = 0;  // bytes on the wire of fragments 0..n-2 (= mtu)
  std::uint32_t last_wire_bytes = 0;  // bytes on the wire of fragment n-1
};

constexpr Fragmentation Fragment(std::uint32_t payload_bytes, std::uint32_t mtu_bytes,
                                 std::uint32_t fragment_header_bytes) {
  const std::uint32_t chunk = mtu_bytes - fragment_header_bytes;
  const auto count = static_cast<std::uint32_t>((std::uint64_t{payload_bytes} + chunk - 1) / chunk);
  return {count, mtu_bytes, payload_bytes - (count - 1) * chunk + fragment_header_bytes};
}

}  // namespace uavsim::channel
