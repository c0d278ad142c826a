// The command line's shared parts: parsing against a command's option
// table, the options several commands share, the table of commands.
#include "apps/cli/cli.h"

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <new>
#include <sstream>

#include "core/error.h"
#include "core/interrupt.h"
#include "sim/version.h"

namespace uavsim::cli {

using core::UsageError;

std::optional<std::string> ParsedArgs::Value(const std::string& f) const {
  auto it = values.find(f);
  if (it == values.end()) return std::nullopt;
  return it->second.back();
}

std::vector<std::string> ParsedArgs::Values(const std::string& f) const {
  auto it = values.find(f);
  return it == values.end() ? std::vector<std::string>{} : it->second;
}

const std::vector<Command>& Commands() {
  static const std::vector<Command> commands{
      ValidateCommand(), RunCommand(),       SweepCommand(),  TrainCommand(),
      DatasetCommand(),  ReproduceCommand(), ReportCommand(), BenchCommand()};
  return commands;
}

ParsedArgs Parse(const Command& command, int argc, char** argv, int first) {
  const std::string& cmd = command.name;
  std::map<std::string, bool> takes_value{{"--help", false}, {"--quiet", false}};
  for (const Option& o : command.options) takes_value[o.name] = o.takes_value;
  ParsedArgs a;
  for (int i = first; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg.size() <= 2 || arg.compare(0, 2, "--") != 0) {
      a.positional.push_back(arg);
      continue;
    }
    std::string name = arg, value;
    bool has_inline = false;
    if (auto eq = arg.find('='); eq != std::string::npos) {
      name = arg.substr(0, eq);
      value = arg.substr(eq + 1);
      has_inline = true;
    }
    const auto option = takes_value.find(name);
    if (option != takes_value.end() && option->second) {
      if (!has_inline) {
        if (i + 1 >= argc) throw UsageError("uavsim " + cmd + ": " + name + " needs a value");
        value = argv[++i];
      }
      a.values[name].push_back(value);
    } else if (option != takes_value.end() && !has_inline) {
      a.flags.insert(name);
    } else {
      throw UsageError("uavsim " + cmd + ": unknown option '" + arg + "' (see uavsim " + cmd +
                       " --help)");
    }
  }
  return a;
}

std::vector<std::string> Overrides(const ParsedArgs& a) { return a.Values("--set"); }

const std::string& OneScenario(const std::string& cmd, const ParsedArgs& a) {
  if (a.positional.size() != 1)
    throw UsageError("uavsim " + cmd + ": expected one scenario file (see uavsim " + cmd +
                     " --help)");
  return a.positional[0];
}

std::vector<std::string> RecordList(const std::string& cmd, const ParsedArgs& a) {
  std::vector<std::string> record;
  if (auto r = a.Value("--record")) {
    std::stringstream ss(*r);
    std::string m;
    while (std::getline(ss, m, ',')) {
      if (m != "camera" && m != "lidar" && m != "radar" && m != "mcap")
        throw UsageError("uavsim " + cmd +
                         ": --record expects a list of camera, lidar, radar, mcap; got '" + m +
                         "'");
      record.push_back(m);
    }
  }
  return record;
}

std::uint64_t UnsignedOption(const std::string& cmd, const std::string& name, const std::string& v,
                             std::uint64_t max) {
  if (v.empty() || v.size() > 19 || v.find_first_not_of("0123456789") != std::string::npos ||
      std::stoull(v) > max)
    throw UsageError("uavsim " + cmd + ": " + name + " expects an integer from 0 to " +
                     std::to_string(max) + ", got '" + v + "'");
  return std::stoull(v);
}

double NumberOption(const std::string& cmd, const std::string& name, const std::string& v,
                    double lo, double hi, const std::string& what) {
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !(x >= lo && x <= hi))
    throw UsageError("uavsim " + cmd + ": " + name + " expects " + what + ", got '" + v + "'");
  return x;
}

std::string Duration(double s) {
  char text[32];
  if (s < 120)
    std::snprintf(text, sizeof text, "%.2g s", s);
  else if (s < 7200)
    std::snprintf(text, sizeof text, "%.2g min", s / 60);
  else
    std::snprintf(text, sizeof text, "%.3g h", s / 3600);
  return text;
}

std::string CommandLine(int argc, char** argv) {
  std::string line = "uavsim";
  for (int i = 1; i < argc; ++i) line += " " + std::string(argv[i]);
  return line;
}

bool& Verbose() {
  static bool verbose = false;
  return verbose;
}

namespace {

// `uavsim --help`: the commands from the table.
std::string MainHelp() {
  std::string out =
      "uavsim: discrete-event network and sensing simulator for edge-assisted multimodal UAV "
      "localization\n"
      "\n"
      "usage: uavsim COMMAND [OPTIONS]\n"
      "\n"
      "commands:\n";
  for (const Command& c : Commands()) {
    char line[256];
    std::snprintf(line, sizeof line, "  %-26s %s\n", c.usage.c_str(), c.summary.c_str());
    out += line;
  }
  return out +
         "\n"
         "options: --help (also after a command), --version, --quiet (every command)\n"
         "exit codes: 0 ok, 1 failure while running, 2 bad input or usage, 130 interrupted\n";
}

}  // namespace

int RunCommandLine(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << MainHelp();
    return kExitBadInput;
  }
  const std::string cmd = argv[1];
  if (cmd == "--help" || cmd == "-h" || cmd == "help") return std::cout << MainHelp(), kExitOk;
  if (cmd == "--version") {
    std::cout << "uavsim " << uavsim::sim::Version();
    if (*uavsim::sim::GitHash()) std::cout << " (" << uavsim::sim::GitHash() << ")";
    std::cout << "\n";
    return kExitOk;
  }
  for (const Command& c : Commands()) {
    if (c.name != cmd) continue;
    if (c.precheck) c.precheck(argc, argv);
    const ParsedArgs a = Parse(c, argc, argv, 2);
    if (a.Has("--help")) return std::cout << c.help(), kExitOk;
    return c.run(a, argc, argv);
  }
  throw UsageError("uavsim: unknown command '" + cmd + "' (see uavsim --help)");
}

int RunMain(int argc, char** argv, std::string (*details)(const std::exception&)) {
  try {
    core::InstallInterruptHandlers();  // again: a library's initialiser may have reset them
    core::ThrowIfInterrupted();        // a request during the libraries' initialisers
    const int rc = RunCommandLine(argc, argv);
    // A request the command did not poll for (it came during its last
    // steps): answered like any other.
    core::ThrowIfInterrupted();
    return rc;
  } catch (const core::ConfigError& e) {
    std::cerr << e.what() << "\n";
    return kExitBadInput;
  } catch (const UsageError& e) {
    std::cerr << e.what() << "\n";
    return kExitBadInput;
  } catch (const core::Interrupted&) {
    std::cerr << "uavsim: interrupted; nothing half-written is left under a final name\n";
    return kExitInterrupted;
  } catch (const std::bad_alloc&) {
    std::cerr << "uavsim: out of memory\n";
    return kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << "uavsim: " << e.what() << "\n";
    if (const std::string more = details ? details(e) : ""; !more.empty())
      std::cerr << more << "\n";
    return kExitFailure;
  }
}

}  // namespace uavsim::cli
