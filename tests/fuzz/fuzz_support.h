// Shared by the libFuzzer targets: runs a loader on the input bytes and sorts
// what it throws. Bad input must end in core::ConfigError (or UsageError)
// whose pointer is empty, a JSON pointer ("/...") or a text position ("line
// L, column C", "byte N"); anything else escaping the loader (an nlohmann
// exception, std::out_of_range, std::bad_alloc, ...) is a finding: it is
// printed and the process aborts, so libFuzzer saves the input as a crash.
// With UAVSIM_FUZZ_VERBOSE set in the environment, refusals are printed too
// (to see why a seed is refused: UAVSIM_FUZZ_VERBOSE=1 build-fuzz/T FILE).
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <typeinfo>

#include "core/error.h"

namespace uavsim::fuzz {

[[noreturn]] inline void Finding(const char* what, const std::string& detail) {
  std::fprintf(stderr, "\n==FUZZ FINDING== %s: %s\n", what, detail.c_str());
  std::fflush(stderr);
  std::abort();
}

// Calls `load(text)`; returns normally when it succeeds or refuses the input
// as documented, aborts otherwise.
template <class Load>
void RunLoader(const std::uint8_t* data, std::size_t size, Load&& load) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    load(text);
  } catch (const core::ConfigError& e) {
    static const bool verbose = std::getenv("UAVSIM_FUZZ_VERBOSE") != nullptr;
    if (verbose) std::fprintf(stderr, "refused: %s\n", e.what());
    const std::string& p = e.pointer();
    const bool located =
        p.empty() || p[0] == '/' || p.rfind("line ", 0) == 0 || p.rfind("byte ", 0) == 0;
    if (e.file().empty() || !located || e.message().empty())
      Finding("ConfigError without file or JSON pointer", e.what());
  } catch (const core::UsageError& e) {
    static const bool verbose = std::getenv("UAVSIM_FUZZ_VERBOSE") != nullptr;
    if (verbose) std::fprintf(stderr, "refused (usage): %s\n", e.what());
  } catch (const std::exception& e) {
    Finding(typeid(e).name(), e.what());
  } catch (...) {
    Finding("unknown exception", "");
  }
}

}  // namespace uavsim::fuzz
