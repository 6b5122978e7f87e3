#pragma once

// A small reader for the measurement files: a header row of column names, then rows of numbers.
// Columns are found by name and extra columns are ignored. Any malformed line is reported with its
// line number (1-based, the header is line 1); nothing is silently skipped or cut short.

#include <charconv>
#include <cstddef>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace mjukf::examples {

/// A CSV file that could not be read; what() names the file and the line.
class CsvError : public std::runtime_error {
 public:
  CsvError(const std::string& path, long line, const std::string& what)
      : std::runtime_error(path + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + what), line_(line) {}
  /// The 1-based line of the problem, 0 when it concerns the whole file.
  long line() const { return line_; }

 private:
  long line_;
};

/// A numeric table, stored by column.
class CsvTable {
 public:
  CsvTable(std::vector<std::string> names, std::vector<std::vector<double>> columns)
      : names_(std::move(names)), columns_(std::move(columns)) {}

  const std::vector<std::string>& names() const { return names_; }
  std::size_t rows() const { return columns_.empty() ? 0 : columns_.front().size(); }
  bool has(std::string_view name) const { return find(name) >= 0; }
  /// The column called `name`; throws std::out_of_range naming it when there is none.
  const std::vector<double>& column(std::string_view name) const {
    const long index = find(name);
    if (index < 0) throw std::out_of_range("no column named '" + std::string(name) + "'");
    return columns_[static_cast<std::size_t>(index)];
  }

 private:
  long find(std::string_view name) const {
    for (std::size_t i = 0; i < names_.size(); ++i)
      if (names_[i] == name) return static_cast<long>(i);
    return -1;
  }

  std::vector<std::string> names_;
  std::vector<std::vector<double>> columns_;
};

namespace detail {

inline std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

template <class Field>
void splitFields(std::string_view line, Field&& field) {
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    field(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) return;
    start = comma + 1;
  }
}

}  // namespace detail

/// Reads a whole CSV file, skipping a leading UTF-8 byte order mark. Throws CsvError with the line number for a missing
/// file, an empty file, a duplicated column name, a row with too few or too many fields, or a field that is not a
/// number (NaN and infinities are accepted as numbers here; loadPlantData refuses them in the columns it uses).
inline CsvTable readCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw CsvError(path, 0, "cannot open the file");
  std::string line;
  if (!std::getline(in, line)) throw CsvError(path, 1, "the file is empty: expected a header row");
  if (line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);  // a UTF-8 byte order mark, as spreadsheets write

  std::vector<std::string> names;
  detail::splitFields(line, [&](std::string_view name) { names.emplace_back(name); });
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i].empty()) throw CsvError(path, 1, "column " + std::to_string(i + 1) + " has no name");
    for (std::size_t j = 0; j < i; ++j)
      if (names[i] == names[j]) throw CsvError(path, 1, "column name '" + names[i] + "' appears twice");
  }

  std::vector<std::vector<double>> columns(names.size());
  long lineNumber = 1;
  long blankLine = 0;  // blank lines may only end the file
  while (std::getline(in, line)) {
    ++lineNumber;
    if (detail::trim(line).empty()) {
      if (blankLine == 0) blankLine = lineNumber;
      continue;
    }
    if (blankLine != 0) throw CsvError(path, blankLine, "blank line inside the data");
    std::size_t field = 0;
    detail::splitFields(line, [&](std::string_view text) {
      if (field >= names.size())
        throw CsvError(path, lineNumber, "more than the " + std::to_string(names.size()) + " fields of the header");
      double value = 0;
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (text.empty() || error != std::errc() || end != text.data() + text.size())
        throw CsvError(path, lineNumber,
                       "field " + std::to_string(field + 1) + " ('" + names[field] + "') is not a number: '" +
                           std::string(text) + "'");
      columns[field++].push_back(value);
    });
    if (field != names.size())
      throw CsvError(path, lineNumber,
                     "has " + std::to_string(field) + " fields, the header has " + std::to_string(names.size()));
  }
  if (in.bad()) throw CsvError(path, lineNumber, "read error");
  return CsvTable(std::move(names), std::move(columns));
}

}  // namespace mjukf::examples
