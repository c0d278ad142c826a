#include "core/zip_check.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <vector>

#include "core/error.h"

namespace uavsim::core {

void RequireWholeZip(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return;
  const auto size = static_cast<std::uint64_t>(in.tellg());
  char head[4] = {};
  in.seekg(0);
  in.read(head, sizeof head);
  if (!in || std::memcmp(head, "PK\x03\x04", 4) != 0) return;  // not one: the loader says so
  // The end-of-central-directory record (22 bytes, then a comment of at
  // most 65535) closes every zip archive.
  const std::uint64_t tail = std::min<std::uint64_t>(size, 22 + 65535);
  std::vector<char> end(tail);
  in.seekg(static_cast<std::streamoff>(size - tail));
  in.read(end.data(), static_cast<std::streamsize>(tail));
  if (in && tail >= 22)
    for (std::uint64_t i = tail - 22 + 1; i-- > 0;)
      if (std::memcmp(end.data() + i, "PK\x05\x06", 4) == 0) return;
  throw ConfigError(path, "",
                    "truncated: its " + std::to_string(size) +
                        " bytes end before the zip archive a .pt file is does (cut short "
                        "while written or copied?)");
}

}  // namespace uavsim::core
