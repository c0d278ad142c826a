// The uavsim command line (DESIGN.md "Command line"): one table of commands,
// each with the options it accepts, its help and its body (a file each in
// apps/cli/). Bad input throws core::UsageError or core::ConfigError; main()
// turns them into one line on stderr and exit code 2.
#pragma once

#include <exception>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace uavsim::cli {

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitInterrupted = 130;

// One option of a command: its name ("--seed") and whether it takes a value.
// Every command also accepts --help and --quiet.
struct Option {
  std::string name;
  bool takes_value = false;
};

// A command line after its command: positional arguments, values of the
// options that take one (every occurrence, in order), flags given.
struct ParsedArgs {
  std::vector<std::string> positional;
  std::map<std::string, std::vector<std::string>> values;
  std::set<std::string> flags;
  bool Has(const std::string& f) const { return flags.count(f) || values.count(f); }
  // The last value given for `f`.
  std::optional<std::string> Value(const std::string& f) const;
  // Every value given for `f` (none: empty).
  std::vector<std::string> Values(const std::string& f) const;
};

// One row of the command table.
struct Command {
  std::string name;
  std::string usage;    // "validate SCENARIO.json": the main help's left column
  std::string summary;  // its right column
  std::vector<Option> options;
  std::string (*help)();  // `uavsim NAME --help`
  // Runs the command; argv is the whole command line (argv[1] is its name).
  int (*run)(const ParsedArgs& args, int argc, char** argv);
  // Checks the raw arguments before they are parsed (may be null).
  void (*precheck)(int argc, char** argv) = nullptr;
};

// `uavsim ARGS...`: finds argv[1] in the table, parses its options and runs
// it (or prints the help, the version); returns the exit code. Bad input
// throws core::UsageError or core::ConfigError; the rest as each command
// says. main() and the Python module (apps/python) call it.
int RunCommandLine(int argc, char** argv);

// A program's main(): RunCommandLine, with bad input, an interruption or a
// failure turned into its one line on stderr and its exit code (2, 130, 1).
// `details`: further lines for a failure (a traceback), or "".
int RunMain(int argc, char** argv, std::string (*details)(const std::exception&) = nullptr);

// The commands, in the order `uavsim --help` lists them.
const std::vector<Command>& Commands();

// Parses argv[first..] against `command`'s options (and --help, --quiet);
// an unknown option or a missing value is a UsageError naming the command.
ParsedArgs Parse(const Command& command, int argc, char** argv, int first);

// --set P=V overrides of the scenario.
std::vector<std::string> Overrides(const ParsedArgs& a);
// The one positional argument, a scenario file.
const std::string& OneScenario(const std::string& cmd, const ParsedArgs& a);
// --record LIST: camera, lidar, radar and mcap, comma-separated (none: empty).
std::vector<std::string> RecordList(const std::string& cmd, const ParsedArgs& a);
// An integer option in [0, max].
std::uint64_t UnsignedOption(const std::string& cmd, const std::string& name, const std::string& v,
                             std::uint64_t max);
// A number in [lo, hi]; `what` says what is expected ("seconds from 1 to 3600").
double NumberOption(const std::string& cmd, const std::string& name, const std::string& v,
                    double lo, double hi, const std::string& what);
// "uavsim ARG1 ARG2 ...", as the model folder and the plan record keep it.
std::string CommandLine(int argc, char** argv);
// "12 s", "3.4 min", "2.1 h".
std::string Duration(double s);

// --verbose of `uavsim run`: a failing TorchScript method's whole traceback
// after its line (main() prints it).
bool& Verbose();

// The commands' rows (apps/cli/<name>_command.cpp: usage, options, help).
Command ValidateCommand();
Command RunCommand();
Command SweepCommand();
Command TrainCommand();
Command DatasetCommand();
Command ReproduceCommand();
Command ReportCommand();
Command BenchCommand();

// The commands' bodies (apps/cli/<name>.cpp), which the rows run. Two
// programs define them: uavsim-main (and the Python module) runs every one;
// uavsim-light, which loads no LibTorch, runs validate and report and hands
// the others, and a validate that must load a model, to uavsim-main in its
// place (apps/cli/light_main.cpp; the launcher picks the program).
int RunValidateCommand(const ParsedArgs& a, int argc, char** argv);
int RunRunCommand(const ParsedArgs& a, int argc, char** argv);
int RunSweepCommand(const ParsedArgs& a, int argc, char** argv);
int RunTrainCommand(const ParsedArgs& a, int argc, char** argv);
int RunDatasetCommand(const ParsedArgs& a, int argc, char** argv);
int RunReproduceCommand(const ParsedArgs& a, int argc, char** argv);
int RunReportCommand(const ParsedArgs& a, int argc, char** argv);
int RunBenchCommand(const ParsedArgs& a, int argc, char** argv);

// train's flags that the training config replaced, refused by name
// (train_command.cpp).
void RefuseReplacedTrainFlags(const ParsedArgs& a);

}  // namespace uavsim::cli
