#pragma once

// Command-line parsing for the example programs: `program SUBCOMMAND --flag value …`.
// Every flag takes exactly one value; unknown flags, missing values and values that do not parse
// throw UsageError, which the programs turn into a usage message and exit code 64.

#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace mjukf::examples {

/// Exit codes of the example programs.
enum ExitCode : int {
  kExitOk = 0,
  kExitFailure = 1,  ///< the run itself failed: a filter refused a step, an output could not be written, gnuplot failed
  kExitBadData = 2,  ///< an input CSV file is malformed or truncated (the message names the line)
  kExitUsage = 64,   ///< unknown subcommand or flag, missing or bad value (sysexits' EX_USAGE)
  /// stopped by a signal: 128 + its number, 129 SIGHUP, 130 SIGINT, 143 SIGTERM (interrupt.hpp)
  kExitSignal = 128,
};

/// The command line was wrong; what() says how.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The `--flag value` pairs of one subcommand, checked against the flags it knows.
class Arguments {
 public:
  Arguments(const std::vector<std::string>& words, const std::set<std::string>& known) {
    for (std::size_t i = 0; i < words.size(); ++i) {
      const std::string& flag = words[i];
      if (known.count(flag) == 0) throw UsageError("unknown flag '" + flag + "'");
      if (i + 1 >= words.size()) throw UsageError("flag " + flag + " needs a value");
      if (!values_.emplace(flag, words[++i]).second) throw UsageError("flag " + flag + " given twice");
    }
  }

  bool has(const std::string& flag) const { return values_.count(flag) != 0; }

  std::string text(const std::string& flag, const std::string& fallback = {}) const {
    const auto it = values_.find(flag);
    return it == values_.end() ? fallback : it->second;
  }

  std::string requiredText(const std::string& flag) const {
    if (!has(flag)) throw UsageError("flag " + flag + " is required");
    return text(flag);
  }

  /// A finite number (or +inf where `allowInfinity`).
  double number(const std::string& flag, double fallback, bool allowInfinity = false) const {
    if (!has(flag)) return fallback;
    return parseNumber(flag, text(flag), allowInfinity);
  }

  /// An integer from `minimum` to `maximum`; the caller's type must hold `maximum` (no silent wrap).
  long integer(const std::string& flag, long fallback, long minimum,
               long maximum = std::numeric_limits<long>::max()) const {
    if (!has(flag)) return fallback;
    const std::string& value = text(flag);
    long result = 0;
    const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), result);
    if (value.empty() || error != std::errc() || end != value.data() + value.size() || result < minimum ||
        result > maximum)
      throw UsageError("flag " + flag + " needs an integer >= " + std::to_string(minimum) +
                       (maximum < std::numeric_limits<long>::max() ? " and <= " + std::to_string(maximum) : "") +
                       ", not '" + value + "'");
    return result;
  }

  /// A comma-separated list of exactly `count` finite numbers.
  std::vector<double> numbers(const std::string& flag, std::size_t count) const {
    std::vector<double> result;
    const std::string all = text(flag);
    std::string_view rest = all;
    for (;;) {
      const std::size_t comma = rest.find(',');
      result.push_back(parseNumber(flag, std::string(rest.substr(0, comma)), false));
      if (comma == std::string_view::npos) break;
      rest.remove_prefix(comma + 1);
    }
    if (result.size() != count)
      throw UsageError("flag " + flag + " needs " + std::to_string(count) + " comma-separated numbers, got " +
                       std::to_string(result.size()));
    return result;
  }

 private:
  static double parseNumber(const std::string& flag, const std::string& value, bool allowInfinity) {
    double result = 0;
    const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), result);
    const bool ok = !value.empty() && error == std::errc() && end == value.data() + value.size() &&
                    (std::isfinite(result) || (allowInfinity && result > 0 && std::isinf(result)));
    if (!ok) throw UsageError("flag " + flag + " needs a finite number, not '" + value + "'");
    return result;
  }

  std::map<std::string, std::string> values_;
};

}  // namespace mjukf::examples
