#pragma once

// Writes CSV files: a header row, then rows of numbers (and plain names) in the shortest form that reads back
// to the same double (std::to_chars), so a simulated file fed to `estimate` loses nothing.

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/atomic_file.hpp"

namespace mjukf::examples {

/// Writes one CSV file under its temporary name (atomic_file.hpp); errors name the file's own path.
class CsvWriter {
 public:
  CsvWriter(const OutputFile& file, const std::vector<std::string>& header)
      : path_(file.path), columns_(header.size()), file_(std::fopen(file.temporary.c_str(), "w")) {
    if (file_ == nullptr) throw OutputError(detail::systemError(path_, "cannot open the file for writing", errno));
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (i > 0) std::fputc(',', file_);
      std::fputs(header[i].c_str(), file_);
    }
    std::fputc('\n', file_);
  }
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;
  ~CsvWriter() {
    if (file_ != nullptr) std::fclose(file_);
  }

  /// Appends one field to the current row.
  CsvWriter& operator<<(double value) {
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    if (field_ > 0) std::fputc(',', file_);
    std::fwrite(buffer, 1, static_cast<std::size_t>(result.ptr - buffer), file_);
    ++field_;
    return *this;
  }

  /// Appends a text field (a name: no comma, quote or line break, so it needs no quoting).
  CsvWriter& operator<<(const std::string& text) {
    if (text.find_first_of(",\"\n\r") != std::string::npos)
      throw std::logic_error(path_ + ": the field '" + text + "' would need quoting");
    if (field_ > 0) std::fputc(',', file_);
    std::fputs(text.c_str(), file_);
    ++field_;
    return *this;
  }

  /// Appends the entries of a vector to the current row.
  template <class Vector>
  CsvWriter& fields(const Vector& values) {
    for (int i = 0; i < static_cast<int>(values.size()); ++i) *this << static_cast<double>(values(i));
    return *this;
  }

  /// Ends the current row; its field count must match the header.
  void endRow() {
    if (field_ != columns_)
      throw std::logic_error(path_ + ": a row of " + std::to_string(field_) + " fields for " +
                             std::to_string(columns_) + " columns");
    std::fputc('\n', file_);
    field_ = 0;
  }

  /// Flushes, syncs and closes; throws OutputError when any write failed (a full disk, for example).
  void close() {
    std::FILE* file = file_;
    file_ = nullptr;
    if (!closeWhole(file)) throw OutputError(detail::systemError(path_, "writing the file failed", errno));
  }

 private:
  std::string path_;
  std::size_t columns_;
  std::size_t field_ = 0;
  std::FILE* file_;
};

/// Column names `prefix1 … prefixN` followed by `suffix`, e.g. ("theta", 2, "_true").
inline std::vector<std::string> numberedNames(const std::string& prefix, int count, const std::string& suffix = {}) {
  std::vector<std::string> names;
  for (int i = 1; i <= count; ++i) names.push_back(prefix + std::to_string(i) + suffix);
  return names;
}

}  // namespace mjukf::examples
