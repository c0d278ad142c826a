// Errors that end a command. ConfigError is bad input (exit code 2) and
// carries the file and JSON pointer it concerns; main catches it once.
#pragma once

#include <stdexcept>
#include <string>

namespace uavsim::core {

// How an error line shows a JSON pointer (RFC 6901, "~" and "/" in keys
// already escaped as ~0 and ~1): as it is, unless it contains a space or
// a colon (which the line's ": " separators would make ambiguous) or is
// "/" (the key "" at the top, which would read as the document itself):
// then as a JSON string, in double quotes with JSON's escapes. Text that
// is not a pointer (no leading "/", e.g. "line 3, column 5") is returned
// as it is.
std::string ShowPointer(const std::string& pointer);

// "FILE: /json/pointer: message", the pointer as ShowPointer shows it.
// `pointer` may be empty (the error is about the file, not a place in it)
// or a location such as "line 3, column 5" for syntax errors; an error
// about the document itself (its root, the empty pointer) is made with
// AboutDocument and reads "FILE: /: message".
class ConfigError : public std::runtime_error {
 public:
  ConfigError(std::string file, std::string pointer, std::string message);
  static ConfigError AboutDocument(std::string file, std::string message);

  const std::string& file() const { return file_; }
  const std::string& pointer() const { return pointer_; }  // "" for the document itself
  const std::string& message() const { return message_; }
  bool about_document() const { return about_document_; }
  // The line without its file: "POINTER: message" (or the message alone).
  std::string Located() const;

 private:
  ConfigError(std::string file, std::string pointer, std::string message, bool about_document);
  std::string file_, pointer_, message_;
  bool about_document_ = false;
};

// A command used wrongly (bad flag, refused output directory): exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace uavsim::core
