#pragma once

// The measurement rows of the reference files (tests/data/reference_measurements.tar.xz, unpacked
// into MJUKF_DATA_DIR by the tests' CMake). For tests that link mjukf_support (the CSV reader).

#include <string>
#include <vector>

#include "common/csv.hpp"

namespace mjukf::testing {

/// The rows y_k of reference file `file` (a name in MJUKF_DATA_DIR), from its columns y1 … ym.
template <class Meas>
std::vector<Meas> referenceMeasurements(const std::string& file) {
  const auto table = mjukf::examples::readCsv(std::string(MJUKF_DATA_DIR) + "/" + file);
  std::vector<Meas> rows(table.rows());
  for (int c = 0; c < Meas::RowsAtCompileTime; ++c) {
    const auto& column = table.column("y" + std::to_string(c + 1));
    for (std::size_t k = 0; k < rows.size(); ++k) rows[k](c) = typename Meas::Scalar(column[k]);
  }
  return rows;
}

}  // namespace mjukf::testing
