#include "core/error.h"

#include <utility>

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

// "POINTER: message", the message alone without a pointer; "/" for the
// document itself.
std::string Locate(const std::string& pointer, bool about_document, const std::string& msg) {
  if (about_document) return "/: " + msg;
  if (pointer.empty()) return msg;
  return ShowPointer(pointer) + ": " + msg;
}

std::string Compose(const std::string& file, const std::string& located) {
  return OneLine((file.empty() ? std::string("<input>") : file) + ": " + located);
}

// `s` as a JSON string literal (quotes, backslashes and control characters
// escaped; other bytes as they are, OneLine shows those that are not UTF-8).
std::string Quoted(const std::string& s) {
  static const char* kHex = "0123456789abcdef";
  std::string out = "\"";
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\')
      out += std::string("\\") + ch;
    else if (c == '\n')
      out += "\\n";
    else if (c == '\r')
      out += "\\r";
    else if (c == '\t')
      out += "\\t";
    else if (c < 0x20 || c == 0x7f)
      out += std::string("\\u00") + kHex[c >> 4] + kHex[c & 15];
    else
      out += ch;
  }
  return out + "\"";
}
}  // namespace

std::string ShowPointer(const std::string& pointer) {
  if (pointer.empty() || pointer[0] != '/') return pointer;
  if (pointer == "/" || pointer.find_first_of(" :") != std::string::npos) return Quoted(pointer);
  return pointer;
}

ConfigError::ConfigError(std::string file, std::string pointer, std::string message)
    : ConfigError(std::move(file), std::move(pointer), std::move(message), false) {}

ConfigError::ConfigError(std::string file, std::string pointer, std::string message,
                         bool about_document)
    : std::runtime_error(Compose(file, Locate(pointer, about_document, message))),
      file_(std::move(file)),
      pointer_(std::move(pointer)),
      message_(std::move(message)),
      about_document_(about_document) {}

ConfigError ConfigError::AboutDocument(std::string file, std::string message) {
  return ConfigError(std::move(file), "", std::move(message), true);
}

std::string ConfigError::Located() const { return Locate(pointer_, about_document_, message_); }

}  // namespace uavsim::core
