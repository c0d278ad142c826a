#include "core/json_io.h"

#include <sys/stat.h>
#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace uavsim::core {
namespace {

constexpr std::size_t kMaxFileBytes = 64u << 20;  // scenarios are small; refuse megabytes of junk
constexpr int kMaxDepth = 64;

std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

// Keeps the path while nlohmann's parser walks the document, to report
// duplicate keys by pointer and to bound nesting (nlohmann keeps the last of
// duplicate keys silently; a scenario that says a thing twice is an error).
class DuplicateKeyGuard {
 public:
  explicit DuplicateKeyGuard(std::string name) : name_(std::move(name)) {}

  bool operator()(int depth, Json::parse_event_t event, Json& parsed) {
    using E = Json::parse_event_t;
    switch (event) {
      case E::object_start:
      case E::array_start:
        if (depth >= kMaxDepth)
          throw ConfigError(name_, Pointer(),
                            "nesting deeper than " + std::to_string(kMaxDepth) + " levels");
        frames_.push_back({event == E::array_start, 0, {}, {}});
        break;
      case E::key: {
        Frame& f = frames_.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second)
          throw ConfigError(name_, Pointer(), "duplicate key \"" + f.key + "\"");
        break;
      }
      case E::object_end:
      case E::array_end:
        frames_.pop_back();
        Advance();
        break;
      case E::value:
        Advance();
        break;
    }
    return true;
  }

  // The pointer of the value being parsed.
  std::string Pointer() const {
    std::string p;
    for (const Frame& f : frames_)
      p += "/" + (f.is_array ? std::to_string(f.index) : EscapePointerToken(f.key));
    return p;
  }

 private:
  struct Frame {
    bool is_array;
    std::size_t index;
    std::set<std::string> keys;
    std::string key;
  };
  void Advance() {
    if (!frames_.empty() && frames_.back().is_array) ++frames_.back().index;
  }
  std::string name_;
  std::vector<Frame> frames_;
};

}  // namespace

std::string FormatNumber(double x) {
  std::ostringstream s;
  s.precision(12);
  s << x;
  return s.str();
}

bool Rule::Contains(double x) const {
  if (min_open ? !(x > min) : !(x >= min)) return false;
  if (max_open ? !(x < max) : !(x <= max)) return false;
  return true;
}

std::string Rule::Describe(bool integer) const {
  const std::string what = integer ? "an integer" : "a number";
  const bool has_min = std::isfinite(min), has_max = std::isfinite(max);
  if (has_min && has_max)
    return what + " in " + (min_open ? "(" : "[") + FormatNumber(min) + ", " + FormatNumber(max) +
           (max_open ? ")" : "]");
  if (has_min) return what + (min_open ? " > " : " >= ") + FormatNumber(min);
  if (has_max) return what + (max_open ? " < " : " <= ") + FormatNumber(max);
  return integer ? "an integer" : "a finite number";
}

std::string EscapePointerToken(const std::string& key) {
  std::string out;
  for (char c : key) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}

std::string DescribeValue(const Json& j) {
  switch (j.type()) {
    case Json::value_t::null:
      return "null";
    case Json::value_t::object:
      return j.empty() ? "an empty object" : "an object";
    case Json::value_t::array:
      return j.empty() ? "an empty array" : "an array of " + std::to_string(j.size());
    case Json::value_t::number_float: {
      const double x = j.get<double>();
      if (std::isnan(x)) return "NaN";
      if (std::isinf(x)) return x > 0 ? "infinity" : "-infinity";
      return FormatNumber(x);
    }
    case Json::value_t::string: {
      std::string s = j.dump(-1, ' ', false, Json::error_handler_t::replace);
      if (s.size() > 48) {
        std::size_t cut = 44;  // on a character's first byte, never inside UTF-8
        while (cut > 0 && (static_cast<unsigned char>(s[cut]) & 0xC0) == 0x80) --cut;
        s = s.substr(0, cut) + "...\"";
      }
      return s;
    }
    default:
      return j.dump();
  }
}

Json ParseJsonText(const std::string& text, const std::string& name) {
  if (text.size() >= 2 &&
      ((text[0] == '\xff' && text[1] == '\xfe') || (text[0] == '\xfe' && text[1] == '\xff')))
    throw ConfigError(name, "", "invalid JSON: the file is UTF-16; save it as UTF-8");
  // nlohmann's lexer takes a NUL byte for the end of the input and would
  // ignore whatever follows it.
  if (const auto nul = text.find('\0'); nul != std::string::npos) {
    const auto line_start = text.rfind('\n', nul);
    const std::size_t line =
        1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + nul, '\n'));
    const std::size_t column = nul - (line_start == std::string::npos ? 0 : line_start + 1) + 1;
    throw ConfigError(name, "line " + std::to_string(line) + ", column " + std::to_string(column),
                      "invalid JSON: NUL byte (is this a binary or UTF-16 file?)");
  }
  DuplicateKeyGuard guard(name);
  try {
    return Json::parse(text, std::ref(guard), /*allow_exceptions=*/true, /*ignore_comments=*/false);
  } catch (const Json::parse_error& e) {
    // nlohmann's message: "[json.exception.parse_error.101] parse error at line 3, column 5: ..."
    std::string msg = e.what();
    const auto at = msg.find(" at line ");
    std::string where = "byte " + std::to_string(e.byte);
    std::string detail = msg;
    if (at != std::string::npos) {
      const auto colon = msg.find(": ", at);
      where = msg.substr(at + 4, colon - at - 4);
      detail = colon == std::string::npos ? "" : msg.substr(colon + 2);
    } else if (const auto p = msg.find("] "); p != std::string::npos) {
      detail = msg.substr(p + 2);
    }
    throw ConfigError(name, where, "invalid JSON: " + detail);
  } catch (const Json::out_of_range& e) {
    // nlohmann refuses numbers beyond double range (1e999) while lexing; its
    // message quotes the literal.
    std::string literal = "a number";
    const std::string what = e.what();
    if (const auto q = what.find('\''); q != std::string::npos) {
      literal = what.substr(q + 1, what.find('\'', q + 1) - q - 1);
      if (literal.size() > 24) literal = literal.substr(0, 20) + "...";
    }
    throw ConfigError(name, guard.Pointer(),
                      "expected a finite number, got " + literal + " (out of range)");
  } catch (const Json::exception& e) {
    throw ConfigError(name, "", std::string("invalid JSON: ") + e.what());
  }
}

Json LoadJsonFile(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw ConfigError(path, "", std::string("cannot read file: ") + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) throw ConfigError(path, "", "cannot read file: is a directory");
  // Devices (/dev/zero), FIFOs and sockets never end or block: refused
  // before they are opened.
  if (!S_ISREG(st.st_mode))
    throw ConfigError(path, "",
                      "cannot read file: not a regular file (a device, FIFO or socket); JSON "
                      "inputs are regular files of at most " +
                          std::to_string(kMaxFileBytes >> 20) + " MiB");
  const auto too_big = [&path](const std::string& size) {
    return ConfigError(path, "",
                       "file is " + size + " bytes; the limit is " + std::to_string(kMaxFileBytes) +
                           " (" + std::to_string(kMaxFileBytes >> 20) + " MiB)");
  };
  if (static_cast<std::size_t>(st.st_size) > kMaxFileBytes)
    throw too_big(std::to_string(st.st_size));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path, "", std::string("cannot read file: ") + std::strerror(errno));
  // Read in blocks, at most one byte past the limit: a file that grows
  // meanwhile stays bounded, and a small file costs a small buffer.
  std::string text;
  std::array<char, 1 << 16> block;
  while (in && text.size() <= kMaxFileBytes) {
    const std::size_t want = std::min(block.size(), kMaxFileBytes + 1 - text.size());
    in.read(block.data(), static_cast<std::streamsize>(want));
    text.append(block.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (text.size() > kMaxFileBytes) throw too_big("more than " + std::to_string(kMaxFileBytes));
  return ParseJsonText(text, path);
}

JsonReader::JsonReader(const Json& node, std::string file, std::string pointer)
    : node_(node), file_(std::move(file)), pointer_(std::move(pointer)) {}

std::string JsonReader::Child(const char* key) const {
  return pointer_ + "/" + EscapePointerToken(key);
}

bool JsonReader::Has(const char* key) const { return node_.contains(key); }

const Json* JsonReader::Find(const char* key) {
  asked_.insert(key);
  auto it = node_.find(key);
  return it == node_.end() ? nullptr : &*it;
}

// The document itself has the empty pointer: its errors say "/".
static ConfigError ErrorAt(const std::string& file, const std::string& pointer,
                           const std::string& message) {
  return pointer.empty() ? ConfigError::AboutDocument(file, message)
                         : ConfigError(file, pointer, message);
}

void JsonReader::Fail(const char* key, const std::string& expected, const Json& got) const {
  throw ErrorAt(file_, key && *key ? Child(key) : pointer_,
                "expected " + expected + ", got " + DescribeValue(got));
}

void JsonReader::Check(bool ok, const char* key, const std::string& message) {
  // Held back until Finish: a misspelt key explains a broken rule better
  // than the rule does ({"from": 40, "too": 50} is about "too", not "to").
  if (!ok && !deferred_) deferred_ = ErrorAt(file_, key && *key ? Child(key) : pointer_, message);
}

void JsonReader::CheckSize(const char* key, std::size_t n, std::size_t min_size,
                           std::size_t max_size) const {
  if (n < min_size || n > max_size) {
    const std::size_t bound = n < min_size ? min_size : max_size;
    const std::string want = (max_size == min_size ? "exactly "
                              : n < min_size       ? "at least "
                                                   : "at most ") +
                             std::to_string(bound) + (bound == 1 ? " element" : " elements");
    throw ConfigError(file_, Child(key),
                      "expected an array of " + want + ", got " + std::to_string(n));
  }
}

double JsonReader::ReadNumber(const char* key, const Json& j, Rule r, bool integer,
                              const std::string& at) const {
  const std::string expected = r.Describe(integer);
  if (!j.is_number())
    throw ConfigError(file_, at, "expected " + expected + ", got " + DescribeValue(j));
  const double x = j.get<double>();
  if (!std::isfinite(x))
    throw ConfigError(file_, at, "expected " + expected + ", got " + DescribeValue(j));
  if (integer && (j.is_number_float() && std::floor(x) != x))
    throw ConfigError(file_, at, "expected " + expected + ", got " + DescribeValue(j));
  if (!r.Contains(x))
    throw ConfigError(file_, at, "expected " + expected + ", got " + DescribeValue(j));
  (void)key;
  return x;
}

void JsonReader::operator()(const char* key, double& v, Rule r) {
  if (const Json* j = Find(key)) v = ReadNumber(key, *j, r, false, Child(key));
}

void JsonReader::operator()(const char* key, int& v, Rule r) {
  r.min = std::max(r.min, double(std::numeric_limits<int>::min()));
  r.max = std::min(r.max, double(std::numeric_limits<int>::max()));
  if (const Json* j = Find(key)) v = static_cast<int>(ReadNumber(key, *j, r, true, Child(key)));
}

void JsonReader::operator()(const char* key, std::int64_t& v, Rule r) {
  r.min = std::max(r.min, -9.0e18);
  r.max = std::min(r.max, 9.0e18);
  if (const Json* j = Find(key)) {
    ReadNumber(key, *j, r, true, Child(key));
    v = j->is_number_integer() ? j->get<std::int64_t>()
                               : static_cast<std::int64_t>(j->get<double>());
  }
}

void JsonReader::operator()(const char* key, std::uint64_t& v) {
  if (const Json* j = Find(key)) {
    if (j->is_number_unsigned() || (j->is_number_integer() && j->get<std::int64_t>() >= 0)) {
      v = j->get<std::uint64_t>();
    } else if (j->is_number_float() && j->get<double>() >= 0 && j->get<double>() < 0x1p53 &&
               std::floor(j->get<double>()) == j->get<double>()) {
      v = static_cast<std::uint64_t>(j->get<double>());  // 7.0: an integer written as a float
    } else {
      Fail(key, "a non-negative integer", *j);
    }
  }
}

void JsonReader::operator()(const char* key, bool& v) {
  if (const Json* j = Find(key)) {
    if (!j->is_boolean()) Fail(key, "true or false", *j);
    v = j->get<bool>();
  }
}

void JsonReader::operator()(const char* key, std::string& v) {
  if (const Json* j = Find(key)) {
    if (!j->is_string()) Fail(key, "a string", *j);
    v = j->get<std::string>();
  }
}

void JsonReader::operator()(const char* key, std::optional<double>& v, Rule r) {
  if (const Json* j = Find(key)) {
    if (j->is_null()) {
      v.reset();
      return;
    }
    if (!j->is_number()) Fail(key, r.Describe(false) + " or null", *j);
    v = ReadNumber(key, *j, r, false, Child(key));
  }
}

namespace {
template <int N>
void ReadFixedVector(JsonReader& rd, const char* key, const Json& j, Rule r, double* out) {
  if (!j.is_array() || j.size() != N)
    rd.Fail(key, "an array of " + std::to_string(N) + " numbers", j);
  for (int i = 0; i < N; ++i) {
    const Json& e = j[i];
    const std::string at = rd.Child(key) + "/" + std::to_string(i);
    if (!e.is_number() || !std::isfinite(e.get<double>()) || !r.Contains(e.get<double>()))
      throw ConfigError(rd.file(), at,
                        "expected " + r.Describe(false) + ", got " + DescribeValue(e));
    out[i] = e.get<double>();
  }
}
}  // namespace

void JsonReader::operator()(const char* key, Eigen::Vector3d& v, Rule r) {
  if (const Json* j = Find(key)) ReadFixedVector<3>(*this, key, *j, r, v.data());
}

void JsonReader::operator()(const char* key, Eigen::Vector2d& v, Rule r) {
  if (const Json* j = Find(key)) ReadFixedVector<2>(*this, key, *j, r, v.data());
}

void JsonReader::operator()(const char* key, std::vector<double>& v, Rule r, std::size_t min_size,
                            std::size_t max_size) {
  const Json* j = Find(key);
  if (!j) return;
  if (!j->is_array()) Fail(key, "an array of numbers", *j);
  CheckSize(key, j->size(), min_size, max_size);
  std::vector<double> out;
  for (std::size_t i = 0; i < j->size(); ++i)
    out.push_back(ReadNumber(key, (*j)[i], r, false, Child(key) + "/" + std::to_string(i)));
  v = std::move(out);
}

void JsonReader::operator()(const char* key, std::vector<Eigen::Vector3d>& v, Rule r,
                            std::size_t min_size, std::size_t max_size) {
  const Json* j = Find(key);
  if (!j) return;
  if (!j->is_array()) Fail(key, "an array of [x, y, z] points", *j);
  CheckSize(key, j->size(), min_size, max_size);
  std::vector<Eigen::Vector3d> out(j->size());
  for (std::size_t i = 0; i < j->size(); ++i) {
    JsonReader elem(*j, file_, Child(key));
    const std::string idx = std::to_string(i);
    ReadFixedVector<3>(elem, idx.c_str(), (*j)[i], r, out[i].data());
  }
  v = std::move(out);
}

void JsonReader::operator()(const char* key, std::vector<std::string>& v,
                            const std::vector<std::string>& allowed) {
  const Json* j = Find(key);
  if (!j) return;
  if (!j->is_array()) Fail(key, "an array of strings", *j);
  std::vector<std::string> out;
  for (std::size_t i = 0; i < j->size(); ++i) {
    const Json& e = (*j)[i];
    const std::string at = Child(key) + "/" + std::to_string(i);
    if (!e.is_string()) throw ConfigError(file_, at, "expected a string, got " + DescribeValue(e));
    std::string s = e.get<std::string>();
    if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), s) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "\"" : ", \"") + a + "\"";
      throw ConfigError(file_, at, "expected one of " + list + ", got " + DescribeValue(e));
    }
    if (std::find(out.begin(), out.end(), s) != out.end())
      throw ConfigError(file_, at, "duplicate entry " + DescribeValue(e));
    out.push_back(std::move(s));
  }
  v = std::move(out);
}

void JsonReader::Finish() const {
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    if (asked_.count(it.key())) continue;
    std::string best;
    std::size_t best_d = SIZE_MAX;
    for (const auto& k : asked_) {
      // A key written without its unit suffix ("rate" for "rate_hz") is as
      // good as a one-letter typo.
      const bool unit_missing = k.size() > it.key().size() &&
                                k.compare(0, it.key().size(), it.key()) == 0 &&
                                k[it.key().size()] == '_';
      const std::size_t d = unit_missing ? 1 : EditDistance(it.key(), k);
      if (d < best_d) best_d = d, best = k;
    }
    std::string msg = "unknown key";
    if (!best.empty() && best_d <= std::max<std::size_t>(2, best.size() / 3))
      msg += " (did you mean \"" + best + "\"?)";
    else if (!asked_.empty()) {
      std::string list;
      for (const auto& k : asked_) list += (list.empty() ? "" : ", ") + k;
      msg += "; known keys here: " + list;
    }
    throw ConfigError(file_, pointer_ + "/" + EscapePointerToken(it.key()), msg);
  }
  if (deferred_) throw *deferred_;
}

}  // namespace uavsim::core
