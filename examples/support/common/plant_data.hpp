#pragma once

// The data the programs exchange: one row per integration step with the measurement y_k and, when
// known, the true state and parameters. Read from and written to CSV files with columns
// t, y1…ym [, x1_true…xn_true] [, theta1_true…thetap_true].

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "common/csv.hpp"
#include "common/csv_writer.hpp"

namespace mjukf::examples {

/// The true parameters over time: `before`, and `after` from row round(changeAt / h) on.
template <class Param>
struct TrueParameters {
  Param before;
  Param after = before;
  double changeAt = std::numeric_limits<double>::infinity();

  // Compared in double: lround of a change time far beyond the run would overflow.
  Param atRow(long row, double h) const {
    return std::isfinite(changeAt) && double(row) >= std::round(changeAt / h) ? after : before;
  }
};

template <class Model>
struct PlantData {
  using State = typename Model::State;
  using Param = typename Model::Param;
  using Meas = typename Model::Meas;

  double stepSize = 0;
  std::vector<Meas> y;
  std::vector<State> stateTruth;      ///< empty when the file has no x*_true columns
  std::vector<Param> parameterTruth;  ///< one per row, always filled
  bool parameterTruthFromFile = false;

  long rows() const { return static_cast<long>(y.size()); }
};

namespace detail {

// Column `name` of `table`, refused at the first missing value (an empty cell or NaN) or infinity: a
// filter would skip one on a row without a measurement and stop half way on one with, and a truth of
// NaN makes a NaN RMSE.
inline const std::vector<double>& finiteColumn(const CsvTable& table, const std::string& path,
                                               const std::string& name) {
  const auto& column = table.column(name);
  for (std::size_t k = 0; k < column.size(); ++k)
    if (!std::isfinite(column[k]))
      throw CsvError(path, table.line(k),
                     "column '" + name + "' " +
                         (std::isnan(column[k]) ? "has a missing value (an empty cell or NaN)"
                                                : "holds " + std::to_string(column[k])) +
                         ": only finite numbers are allowed");
  return column;
}

// Copies columns `prefix1…prefixN suffix` of `table` into a vector of fixed-size vectors.
template <class Vector>
std::vector<Vector> readVectors(const CsvTable& table, const std::string& path, const std::string& prefix,
                                const std::string& suffix) {
  std::vector<Vector> rows(table.rows());
  for (int c = 0; c < Vector::RowsAtCompileTime; ++c) {
    const auto& column = finiteColumn(table, path, prefix + std::to_string(c + 1) + suffix);
    for (std::size_t k = 0; k < rows.size(); ++k) rows[k](c) = column[k];
  }
  return rows;
}

inline std::string joinNames(const std::vector<std::string>& names) {
  std::string text;
  for (const auto& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

// A data file of the plant has the columns t and y1…ym, and x1_true…xn_true and theta1_true…thetap_true
// each all or none, in any order; anything else (another plant's file, a misspelt name) is refused with
// the columns expected, found, missing and not the plant's, as a file that merely contains the columns
// wanted (the robot's y1…y4 hold the tank's y1, y2) would be read as the wrong plant's data.
template <class Model>
void requirePlantColumns(const CsvTable& table, const std::string& path, const std::string& plant) {
  std::vector<std::string> required{"t"};
  for (const auto& name : numberedNames("y", Model::MeasDim)) required.push_back(name);
  const std::vector<std::string> groups[] = {numberedNames("x", Model::StateDim, "_true"),
                                             numberedNames("theta", Model::ParamDim, "_true")};
  std::vector<std::string> missing, unexpected;
  for (const auto& name : required)
    if (!table.has(name)) missing.push_back(name);
  std::string expected = joinNames(required);
  for (const auto& group : groups) {
    std::size_t found = 0;
    for (const auto& name : group) found += table.has(name) ? 1 : 0;
    for (const auto& name : group)
      if (found != 0 && !table.has(name)) missing.push_back(name);
    expected += " [" + joinNames(group) + "]";
  }
  for (const auto& name : table.names()) {
    bool known = std::find(required.begin(), required.end(), name) != required.end();
    for (const auto& group : groups) known = known || std::find(group.begin(), group.end(), name) != group.end();
    if (!known) unexpected.push_back(name);
  }
  if (missing.empty() && unexpected.empty()) return;
  throw CsvError(path, 1,
                 "the columns do not match the plant (" + plant + ")\n  expected: " + expected +
                     " (a part in brackets all or none)\n  found:    " + joinNames(table.names()) +
                     (missing.empty() ? "" : "\n  missing:  " + joinNames(missing)) +
                     (unexpected.empty() ? "" : "\n  not the plant's: " + joinNames(unexpected)));
}

}  // namespace detail

/// Reads a measurement file of the plant `plant` (its name, for messages). Requires the columns t and
/// y1…ym, and x*_true and theta*_true all or none (no other column), and one row per step of `h`
/// starting at t = 0; when the theta*_true columns are absent, the parameter truth is `fallbackTruth`.
/// Throws CsvError (with the line number) for anything malformed, NaN and infinities in the columns it
/// reads included (the whole file is checked before any estimation starts).
template <class Model>
PlantData<Model> loadPlantData(const std::string& path, const std::string& plant, double h,
                               const typename Model::Param& fallbackTruth) {
  const CsvTable table = readCsv(path);
  detail::requirePlantColumns<Model>(table, path, plant);
  if (table.rows() == 0) throw CsvError(path, 2, "no data rows after the header");

  // The schedule pairs row k with t_k = k h: a file on another grid would be silently misread.
  const auto& t = detail::finiteColumn(table, path, "t");
  for (std::size_t k = 0; k < t.size(); ++k) {
    const double expected = static_cast<double>(k) * h;
    if (!(std::abs(t[k] - expected) <= 0.25 * h))
      throw CsvError(path, table.line(k),
                     "t = " + std::to_string(t[k]) + ", but row " + std::to_string(k) +
                         " must be at t = " + std::to_string(expected) +
                         " (one row per step of h = " + std::to_string(h) + " s from t = 0; see --step)");
  }

  PlantData<Model> data;
  data.stepSize = h;
  data.y = detail::readVectors<typename Model::Meas>(table, path, "y", "");
  if (table.has("x1_true")) data.stateTruth = detail::readVectors<typename Model::State>(table, path, "x", "_true");
  data.parameterTruthFromFile = table.has("theta1_true");
  if (data.parameterTruthFromFile)
    data.parameterTruth = detail::readVectors<typename Model::Param>(table, path, "theta", "_true");
  else
    data.parameterTruth.assign(table.rows(), fallbackTruth);
  return data;
}

/// Writes `data` as t, y1…ym, then x*_true when known, then theta*_true, to `file` (atomic_file.hpp).
template <class Model>
void writePlantData(const OutputFile& file, const PlantData<Model>& data) {
  std::vector<std::string> header{"t"};
  for (const auto& names :
       {numberedNames("y", Model::MeasDim),
        data.stateTruth.empty() ? std::vector<std::string>{} : numberedNames("x", Model::StateDim, "_true"),
        numberedNames("theta", Model::ParamDim, "_true")})
    header.insert(header.end(), names.begin(), names.end());
  CsvWriter out(file, header);
  for (long k = 0; k < data.rows(); ++k) {
    const auto row = static_cast<std::size_t>(k);
    out << static_cast<double>(k) * data.stepSize;
    out.fields(data.y[row]);
    if (!data.stateTruth.empty()) out.fields(data.stateTruth[row]);
    out.fields(data.parameterTruth[row]);
    out.endRow();
  }
  out.close();
}

}  // namespace mjukf::examples
