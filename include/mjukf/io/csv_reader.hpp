#pragma once

/// \file
/// `readCsv`: recorded data from a CSV file, a header row of column names and then one row of numbers
/// per sample, read by column name (docs/real-data.md). Not part of the core: `mjukf.hpp` does not
/// include it, since it reads files with iostreams and allocates, which firmware never does.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "mjukf/settings_error.hpp"  // MJUKF_EXCEPTIONS

namespace mjukf::io {

/// Why and where a CSV file could not be read; a default value is "no problem" (false).
struct CsvProblem {
  std::string source;      ///< The file's path (or the name given to `parseCsv`).
  long line = 0;           ///< 1-based line of the file; 0 when the whole file is concerned.
  long column = 0;         ///< 1-based column; 0 when no single column is concerned.
  std::string columnName;  ///< The column's name, when it has one (a cell beyond the header has none).
  std::string reason;      ///< What is wrong; empty when there is no problem.

  /// True when there is a problem.
  explicit operator bool() const noexcept { return !reason.empty(); }

  /// "<source>:<line>: column <column> '<columnName>': <reason>", leaving out the parts not known.
  std::string message() const {
    std::string text = source;
    if (line > 0) text += ":" + std::to_string(line);
    text += ": ";
    if (column > 0) {
      text += "column " + std::to_string(column);
      if (!columnName.empty()) text += " '" + columnName + "'";
      text += ": ";
    }
    return text + reason;
  }
};

/// A CSV file that could not be read: `what()` is `problem().message()`, with the file, the line and,
/// where one is concerned, the column (index and name).
class CsvError : public std::runtime_error {
 public:
  /// The error of `problem`.
  explicit CsvError(CsvProblem problem) : std::runtime_error(problem.message()), problem_(std::move(problem)) {}
  /// A problem of line `line` of `source` as a whole, e.g. one the caller finds in the values it read.
  CsvError(std::string source, long line, std::string reason)
      : CsvError(CsvProblem{std::move(source), line, 0, {}, std::move(reason)}) {}

  /// Where and why, field by field.
  const CsvProblem& problem() const noexcept { return problem_; }
  /// The 1-based line, 0 when the whole file is concerned.
  long line() const noexcept { return problem_.line; }
  /// The 1-based column, 0 when no single column is concerned.
  long column() const noexcept { return problem_.column; }
  /// The column's name, empty when there is none.
  const std::string& columnName() const noexcept { return problem_.columnName; }

 private:
  CsvProblem problem_;
};

class CsvTable;
CsvTable parseCsv(std::string_view text, const std::string& source, CsvProblem& problem);

/// A table of numbers read from a CSV file, stored by column; a missing sample is a quiet NaN.
class CsvTable {
 public:
  /// An empty table: no columns, no rows.
  CsvTable() = default;

  /// The file's path (or the name given to `parseCsv`).
  const std::string& source() const noexcept { return source_; }
  /// The column names, in the file's order, without quotes.
  const std::vector<std::string>& names() const noexcept { return names_; }
  /// The number of rows (samples) of every column.
  std::size_t rows() const noexcept { return lines_.size(); }
  /// The 1-based line of the header row (after any blank lines).
  long headerLine() const noexcept { return headerLine_; }
  /// The 1-based line of the file that row `row` (0-based) was read from; blank lines are skipped, so
  /// it is not always `row + 2`. Requires `row < rows()`.
  long line(std::size_t row) const { return lines_.at(row); }

  /// True when the file has a column called `name`.
  bool has(std::string_view name) const noexcept { return find(name) != nullptr; }
  /// The column called `name`, or null when there is none.
  const std::vector<double>* find(std::string_view name) const noexcept {
    const auto it = std::find(names_.begin(), names_.end(), name);
    return it == names_.end() ? nullptr : &columns_[static_cast<std::size_t>(it - names_.begin())];
  }
  /// The column called `name`. When there is none: throws CsvError naming it and the columns the file
  /// has (exceptions on), otherwise traps; without exceptions, check first with `require`.
  const std::vector<double>& column(std::string_view name) const {
    if (const auto* values = find(name)) return *values;
#if MJUKF_EXCEPTIONS
    throw CsvError(require({name}));
#else
    __builtin_trap();
#endif
  }
  /// The problem of the first of `names` the file lacks, naming it and listing the columns the file has;
  /// no problem (false) when it has them all.
  CsvProblem require(std::initializer_list<std::string_view> names) const {
    for (const std::string_view name : names) {
      if (has(name)) continue;
      std::string present;
      for (const auto& other : names_) present += (present.empty() ? "" : ", ") + other;
      return {source_, headerLine_, 0, std::string(name),
              "no column named '" + std::string(name) + "'; the columns are: " + present};
    }
    return {};
  }

 private:
  friend CsvTable parseCsv(std::string_view text, const std::string& source, CsvProblem& problem);

  std::string source_;
  std::vector<std::string> names_;
  std::vector<std::vector<double>> columns_;
  std::vector<long> lines_;  // the file line of each row
  long headerLine_ = 0;
};

/// \cond INTERNAL
namespace detail {

inline std::string_view trimBlanks(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

struct CsvCell {
  std::string text;
  bool quoted = false;
};

// Splits one line (without its line ending) into cells at commas. A cell in double quotes may hold
// commas, and "" for a quote. Returns the reason and sets `column` (1-based) when a quote is unclosed
// or followed by other text.
inline std::string splitCsvLine(std::string_view line, std::vector<CsvCell>& cells, long& column) {
  cells.clear();
  std::size_t at = 0;
  for (;;) {
    column = static_cast<long>(cells.size()) + 1;
    CsvCell cell;
    while (at < line.size() && (line[at] == ' ' || line[at] == '\t')) ++at;
    if (at < line.size() && line[at] == '"') {
      cell.quoted = true;
      for (++at;; ++at) {
        if (at >= line.size()) return "a quote is not closed (a quoted cell cannot span lines)";
        if (line[at] != '"') {
          cell.text += line[at];
        } else if (at + 1 < line.size() && line[at + 1] == '"') {
          cell.text += '"';
          ++at;
        } else {
          break;
        }
      }
      ++at;
      while (at < line.size() && (line[at] == ' ' || line[at] == '\t')) ++at;
      if (at < line.size() && line[at] != ',') return "text after the closing quote";
    } else {
      const std::size_t comma = std::min(line.find(',', at), line.size());
      cell.text = std::string(trimBlanks(line.substr(at, comma - at)));
      at = comma;
    }
    cells.push_back(std::move(cell));
    if (at >= line.size()) return {};
    ++at;  // the comma
  }
}

// "1 cell", "2 cells".
inline std::string countOf(std::size_t count, const char* noun) {
  return std::to_string(count) + " " + noun + (count == 1 ? "" : "s");
}

// A cell's text quoted for a message, cut short: a binary file must not make a message of megabytes.
inline std::string quotedForMessage(std::string_view text) {
  constexpr std::size_t kShown = 40;
  return "'" + std::string(text.substr(0, kShown)) + (text.size() > kShown ? "...'" : "'");
}

// The value of a cell: empty, or any NaN, is a missing sample (a quiet NaN); otherwise the whole cell
// must be one number in the C locale's format (std::from_chars, whatever the global locale), with an
// optional leading '+'. Returns the reason when it is not.
inline std::string parseCsvNumber(std::string_view text, double& value) {
  if (text.empty()) {
    value = std::numeric_limits<double>::quiet_NaN();
    return {};
  }
  std::string_view digits = text;
  if (digits.size() > 1 && digits[0] == '+' && digits[1] != '-' && digits[1] != '+') digits.remove_prefix(1);
  const char* const end = digits.data() + digits.size();
  const auto [stop, error] = std::from_chars(digits.data(), end, value);
  if (error == std::errc::result_out_of_range) return quotedForMessage(text) + " is out of the range of double";
  if (error != std::errc() || stop == digits.data()) return quotedForMessage(text) + " is not a number";
  if (stop != end)
    return quotedForMessage(text) + " is not a number: " + quotedForMessage({stop, std::size_t(end - stop)}) +
           " follows " + quotedForMessage({digits.data(), std::size_t(stop - digits.data())});
  if (std::isnan(value)) value = std::numeric_limits<double>::quiet_NaN();  // -nan and nan(…) alike
  return {};
}

}  // namespace detail
/// \endcond

/// Parses CSV `text`, named `source` in problems. On a problem, sets `problem` (line, column, reason)
/// and returns an empty table; otherwise clears it. Never throws CsvError.
///
/// The first line that is not blank is the header: the column names, quoted or not, none empty, none
/// twice. Every other line that is not blank is a row with one cell per column; a separator at the end
/// of a line (one cell more, empty) is allowed. Lines end in LF or CRLF; a UTF-8 byte order mark before
/// the header is skipped. A cell is a number (std::from_chars: locale-independent, `inf` accepted), or
/// missing: empty, or `NaN`/`nan` (a quiet NaN either way). A row with too few or too many cells, a cell
/// that is not a number or has text after it, and a number out of the range of double are problems.
inline CsvTable parseCsv(std::string_view text, const std::string& source, CsvProblem& problem) {
  problem = {};
  const auto fail = [&](long line, long column, std::string name, std::string reason) {
    problem = {source, line, column, std::move(name), std::move(reason)};
    return CsvTable();
  };
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // a UTF-8 byte order mark

  CsvTable table;
  table.source_ = source;
  std::vector<detail::CsvCell> cells;
  long lineNumber = 0;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t newline = std::min(text.find('\n', at), text.size());
    std::string_view line = text.substr(at, newline - at);
    at = newline + 1;
    ++lineNumber;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (detail::trimBlanks(line).empty()) continue;

    long column = 0;
    const std::string reason = detail::splitCsvLine(line, cells, column);
    if (!reason.empty()) {
      const bool named = table.headerLine_ != 0 && column <= static_cast<long>(table.names_.size());
      return fail(lineNumber, column, named ? table.names_[static_cast<std::size_t>(column - 1)] : "", reason);
    }
    // A separator at the end of the line leaves one more cell, empty and unquoted: not a column.
    const bool trailingSeparator = cells.size() > 1 && cells.back().text.empty() && !cells.back().quoted;

    if (table.headerLine_ == 0) {
      table.headerLine_ = lineNumber;
      if (trailingSeparator) cells.pop_back();
      for (std::size_t c = 0; c < cells.size(); ++c) {
        const long index = static_cast<long>(c) + 1;
        if (cells[c].text.empty()) return fail(lineNumber, index, "", "the header gives this column no name");
        const auto same = std::find(table.names_.begin(), table.names_.end(), cells[c].text);
        if (same != table.names_.end())
          return fail(lineNumber, index, cells[c].text,
                      "the name is also that of column " + std::to_string(same - table.names_.begin() + 1));
        table.names_.push_back(cells[c].text);
      }
      table.columns_.resize(table.names_.size());
      continue;
    }

    const std::size_t n = table.names_.size();
    if (trailingSeparator && cells.size() == n + 1) cells.pop_back();
    const std::string counts =
        "the line has " + detail::countOf(cells.size(), "cell") + ", the header " + detail::countOf(n, "column");
    if (cells.size() > n) return fail(lineNumber, static_cast<long>(n) + 1, "", "too many cells: " + counts);
    if (cells.size() < n)
      return fail(lineNumber, static_cast<long>(cells.size()) + 1, table.names_[cells.size()], "missing: " + counts);
    for (std::size_t c = 0; c < n; ++c) {
      double value = 0;
      const std::string bad = detail::parseCsvNumber(cells[c].text, value);
      if (!bad.empty()) return fail(lineNumber, static_cast<long>(c) + 1, table.names_[c], bad);
      table.columns_[c].push_back(value);
    }
    table.lines_.push_back(lineNumber);
  }
  if (table.headerLine_ == 0) return fail(1, 0, "", "no header row: the file is empty or blank");
  return table;
}

/// Reads the CSV file at `path` as `parseCsv` does its text. On a problem (the file cannot be read,
/// or what `parseCsv` refuses), sets `problem` and returns an empty table; otherwise clears it.
/// Never throws CsvError.
inline CsvTable readCsv(const std::string& path, CsvProblem& problem) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    problem = {path, 0, 0, {}, "cannot open the file"};
    return {};
  }
  std::string text;
  char buffer[1 << 14];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) text.append(buffer, static_cast<std::size_t>(in.gcount()));
  if (in.bad()) {  // e.g. a directory
    problem = {path, 0, 0, {}, "cannot read the file"};
    return {};
  }
  return parseCsv(text, path, problem);
}

#if MJUKF_EXCEPTIONS
/// `parseCsv(text, source, problem)`, throwing the problem as a CsvError.
inline CsvTable parseCsv(std::string_view text, const std::string& source) {
  CsvProblem problem;
  CsvTable table = parseCsv(text, source, problem);
  if (problem) throw CsvError(std::move(problem));
  return table;
}

/// `readCsv(path, problem)`, throwing the problem as a CsvError.
inline CsvTable readCsv(const std::string& path) {
  CsvProblem problem;
  CsvTable table = readCsv(path, problem);
  if (problem) throw CsvError(std::move(problem));
  return table;
}
#endif

}  // namespace mjukf::io
