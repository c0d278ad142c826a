// Files that appear all at once: written under a temporary name in the same
// folder and renamed into place, so a reader (or a killed writer) never sees
// a half-written file under its final name.
#pragma once

#include <functional>
#include <string>

namespace uavsim::core {

// Writes `content` to `path` atomically. Throws std::runtime_error naming
// the path on failure (the temporary file is removed).
void WriteFileAtomic(const std::string& path, const std::string& content);

// For writers that insist on a file name of their own (torch::save): calls
// `write(temp)` with the temporary path "<path>.tmp-PID", then renames it
// into place (the temporary's stem is <path>'s file name, which torch::save
// writes into the archive). Whatever `write` throws is rethrown after the temporary file is
// removed; a failed rename throws std::runtime_error naming `path`.
void WriteViaTemporary(const std::string& path,
                       const std::function<void(const std::string&)>& write);

// The whole content of the file at `path`, as bytes. Throws
// std::runtime_error "<path>: cannot read" if it cannot be opened.
std::string ReadFileBytes(const std::string& path);

}  // namespace uavsim::core
