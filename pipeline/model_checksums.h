// A model folder's checksums: checksums.sha256 beside model.json, in the
// format of `sha256sum` ("<64 hex>  <file name>" per line, names sorted), so
// that `sha256sum -c checksums.sha256` checks a folder too. The trainer
// writes it last, over every regular file of the folder; loading a model
// verifies every file it lists, so a changed or corrupted file is refused
// instead of running silently with other weights. A folder without it
// (written before checksums existed) loads unchecked. Torch-free header.
#pragma once

#include <string>

namespace uavsim::pipeline {

inline constexpr const char* kModelChecksumsFile = "checksums.sha256";

// Writes `folder`/checksums.sha256 atomically over the folder's regular
// files (not itself). Throws std::runtime_error on I/O failure.
void WriteModelChecksums(const std::string& folder);

// Verifies `folder`/checksums.sha256 if there is one. Throws
// core::ConfigError naming that file and the line of a malformed entry, a
// listed file that is missing, or one whose digest differs (with both).
void VerifyModelChecksums(const std::string& folder);

}  // namespace uavsim::pipeline
