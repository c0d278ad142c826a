#include "sim/core/error.h"

namespace uavsim::core {
namespace {

// One line of valid UTF-8 whatever the input: control characters are escaped
// JSON-style and bytes that are not UTF-8 are shown as \xNN.
std::string OneLine(const std::string& in) {
  static const char* kHex = "0123456789abcdef";
  std::string out;
  for (std::size_t i = 0; i < in.size();) {
    const auto c = static_cast<unsigned char>(in[i]);
    if (c < 0x80) {
      if (c == '\n')
        out += "\\n";
      else if (c == '\r')
        out += "\\r";
      else if (c == '\t')
        out += "\\t";
      else if (c < 0x20 || c == 0x7f)
        out += std::string("\\u00") + kHex[c >> 4] + kHex[c & 15];
      else
        out += static_cast<char>(c);
      ++i;
      continue;
    }
    std::size_t len = 0;  // length of the sequence this lead byte starts; 0 if not a lead byte
    if (c >= 0xc2 && c <= 0xdf)
      len = 2;
    else if (c >= 0xe0 && c <= 0xef)
      len = 3;
    else if (c >= 0xf0 && c <= 0xf4)
      len = 4;
    bool ok = len > 0 && i + len <= in.size();
    for (std::size_t k = 1; ok && k < len; ++k)
      ok = (static_cast<unsigned char>(in[i + k]) & 0xc0) == 0x80;
    if (ok) {
      out.append(in, i, len);
      i += len;
    } else {
      out += std::string("\\x") + kHex[c >> 4] + kHex[c & 15];
      ++i;
    }
  }
  return out;
}

std::string Compose(const std::string& file, const std::string& pointer, const std::string& msg) {
  std::string s = file.empty() ? std::string("<input>") : file;
  s += ": ";
  if (!pointer.empty()) s += pointer + ": ";
  s += msg;
  return OneLine(s);
}
}  // namespace

ConfigError::ConfigError(std::string file, std::string pointer, std::string message)
    : std::runtime_error(Compose(file, pointer, message)),
      file_(std::move(file)),
      pointer_(std::move(pointer)),
      message_(std::move(message)) {}

}  // namespace uavsim::core
