// SHA-256 (FIPS 180-4) through OpenSSL's libcrypto, for checking that files
// are what was written (model folders: pipeline/model_checksums.h).
// Digests are 64 lowercase hex digits, as `sha256sum` prints them.
#pragma once

#include <string>

namespace uavsim::core {

std::string Sha256Hex(const std::string& bytes);

// The digest of the file at `path`, read in blocks. Throws
// std::runtime_error "<path>: cannot read" if it cannot be read.
std::string Sha256FileHex(const std::string& path);

}  // namespace uavsim::core
