#pragma once

// The measurement files, read with the library's CSV reader (mjukf/io/csv_reader.hpp): a header row of
// column names, then rows of numbers; columns are found by name, extra columns are ignored, and any
// malformed line is reported with its line number (the header is line 1). The programs add one rule:
// a row per integration step, so a blank line may only end the file, where elsewhere it would hide a
// lost row.

#include <cstddef>
#include <string>

#include "mjukf/io/csv_reader.hpp"

namespace mjukf::examples {

using io::CsvError;
using io::CsvTable;

/// Reads a whole CSV file as io::readCsv does (an empty cell is NaN, which loadPlantData refuses in the
/// columns it uses), and refuses a blank line before the header or between two rows.
inline CsvTable readCsv(const std::string& path) {
  CsvTable table = io::readCsv(path);
  if (table.headerLine() != 1) throw CsvError(path, 1, "blank line before the header");
  for (std::size_t k = 0; k < table.rows(); ++k) {
    const long expected = static_cast<long>(k) + 2;  // the header, then no blank line
    if (table.line(k) != expected) throw CsvError(path, expected, "blank line inside the data");
  }
  return table;
}

}  // namespace mjukf::examples
