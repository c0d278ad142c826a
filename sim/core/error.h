// Errors that end a command. ConfigError is bad input (exit code 2) and
// carries the file and JSON pointer it concerns; main catches it once.
#pragma once

#include <stdexcept>
#include <string>

namespace uavsim::core {

// "FILE: /json/pointer: message". `pointer` may be empty (whole document) or a
// location such as "line 3, column 5" for syntax errors.
class ConfigError : public std::runtime_error {
 public:
  ConfigError(std::string file, std::string pointer, std::string message);

  const std::string& file() const { return file_; }
  const std::string& pointer() const { return pointer_; }
  const std::string& message() const { return message_; }

 private:
  std::string file_, pointer_, message_;
};

// A command used wrongly (bad flag, refused output directory): exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace uavsim::core
