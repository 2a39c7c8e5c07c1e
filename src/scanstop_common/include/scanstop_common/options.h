#pragma once
/// One small command-line parser for every scanstop tool (issue #22 class 7): strict numbers (no
/// trailing garbage, no overflow, no NaN/Inf, a range), `--help`/`-h` before anything else happens,
/// unknown options named, and JSON helpers that never print a bare nan/inf.
///
///   Options opts("plan_step", "usage: plan_step MAP_DIR OUT_DIR [--scale N]\n...");
///   opts.positional("MAP_DIR", map_dir).integer("--scale", scale, 1, 16).flag("--json", json);
///   if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;   // 0 after --help, 2 on bad usage
///
/// Errors read "--max-iterations 99999999999: not an integer in [1, 100000]".

#include <cstddef>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace scanstop {

/// Exit status of every tool for bad arguments (usage errors).
constexpr int kExitUsage = 2;

/// Parses a whole string as an integer in [min, max]; throws ConfigError
/// "<what> <text>: not an integer in [min, max]" (overflow, trailing characters, empty, out of range).
long long parseIntegerArg(const std::string& what, const std::string& text, long long min, long long max);
/// Parses a whole string as a finite number in [min, max]; throws ConfigError
/// "<what> <text>: not a number in [min, max]" (trailing characters, NaN, Inf, empty, out of range).
double parseRealArg(const std::string& what, const std::string& text, double min, double max);
/// Parses `count` comma-separated finite numbers, each in [min, max]; throws ConfigError naming the
/// option, the text, which value is bad and the expected form (e.g. "x,y,yaw").
std::vector<double> parseRealListArg(const std::string& what, const std::string& text, size_t count, double min,
                                     double max, const std::string& form);

/// A number as JSON: "null" for NaN and infinities (JSON has neither), else printf("%.*g").
std::string jsonNumber(double value, int precision = 9);
/// A string as a JSON string literal (quotes, backslashes and control characters escaped).
std::string jsonString(const std::string& text);

class Options {
 public:
  /// program: the tool's name (message prefix); usage: the full usage text printed by --help.
  Options(std::string program, std::string usage);

  /// A flag without value.
  Options& flag(const std::string& name, bool& target, bool value = true);
  /// An integer option in [min, max].
  Options& integer(const std::string& name, int& target, int min, int max);
  Options& integer(const std::string& name, long& target, long min, long max);
  Options& integer(const std::string& name, size_t& target, size_t min, size_t max);
  /// A finite number in [min, max]; target = value * scale (e.g. degrees given, radians stored).
  Options& real(const std::string& name, double& target, double min, double max, double scale = 1.0);
  /// A string option (any non-empty text that does not start with "--").
  Options& text(const std::string& name, std::string& target);
  /// One of the allowed words.
  Options& choice(const std::string& name, std::string& target, const std::vector<std::string>& allowed);
  /// Any option whose value a function parses (throwing ConfigError for a bad one).
  Options& custom(const std::string& name, const std::function<void(const std::string&)>& parse);
  /// A positional argument, in the order declared; required ones must all be given.
  Options& positional(const std::string& name, std::string& target, bool required = true);
  /// Any number of further positional arguments (after the declared ones).
  Options& rest(const std::string& name, std::vector<std::string>& target);

  /// Parses argv[1..argc). Returns -1 when the tool should go on; 0 after --help/-h (usage printed to
  /// `out`, nothing else done: --help anywhere wins over every other argument); kExitUsage (2) after
  /// a bad argument (message naming it and the usage printed to `err`).
  int parse(int argc, const char* const* argv, std::ostream& out, std::ostream& err) const;
  int parse(int argc, char** argv) const;
  /// Like parse, but throws ConfigError for a bad argument and returns false after --help (usage
  /// printed to `out`).
  bool parseOrThrow(int argc, const char* const* argv, std::ostream& out) const;

  const std::string& usage() const { return usage_; }

 private:
  struct Option {
    std::string name;
    bool takes_value = true;
    std::function<void(const std::string&)> apply;
  };
  const Option* find(const std::string& name) const;
  std::string program_, usage_;
  std::vector<Option> options_;
  struct Positional {
    std::string name;
    std::string* target;
    bool required;
  };
  std::vector<Positional> positionals_;
  std::vector<std::string>* rest_ = nullptr;
  std::string rest_name_;
};

}  // namespace scanstop
