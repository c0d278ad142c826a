// Whether a file is a whole zip archive, as LibTorch's .pt files are
// (torch.save and torch.jit.save write zip archives): a cheap check before
// loading one, so that a file cut short is refused as truncated rather
// than with LibTorch's "PytorchStreamReader failed reading zip archive".
#pragma once

#include <string>

namespace uavsim::core {

// Throws core::ConfigError naming `path` when a file that starts as a zip
// archive has no end-of-archive record in its last 64 KiB + 22 bytes
// ("truncated: its N bytes end before the zip archive ... does"). Does
// nothing for a file it cannot open or that is no zip archive at all (the
// loader reports those).
void RequireWholeZip(const std::string& path);

}  // namespace uavsim::core
