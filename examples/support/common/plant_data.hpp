#pragma once

// The data the programs exchange: one row per integration step with the measurement y_k and, when
// known, the true state and parameters. Read from and written to CSV files with columns
// t, y1…ym [, x1_true…xn_true] [, theta1_true…thetap_true].

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

// Whether the table has all, none, or only some of the columns `prefix1…prefixN suffix`.
inline int countColumns(const CsvTable& table, const std::string& prefix, int n, const std::string& suffix) {
  int found = 0;
  for (int c = 1; c <= n; ++c) found += table.has(prefix + std::to_string(c) + suffix) ? 1 : 0;
  return found;
}

}  // namespace detail

/// Reads a measurement file. Requires columns t and y1…ym and one row per step of `h` starting at
/// t = 0; takes x*_true and theta*_true when all of them are present, else the parameter truth is
/// `fallbackTruth`. Throws CsvError (with the line number) for anything malformed, NaN and infinities
/// in the columns it reads included (the whole file is checked before any estimation starts).
template <class Model>
PlantData<Model> loadPlantData(const std::string& path, double h, const typename Model::Param& fallbackTruth) {
  const CsvTable table = readCsv(path);
  const auto requireAllOrNone = [&](const std::string& prefix, int n, const std::string& suffix) {
    const int found = detail::countColumns(table, prefix, n, suffix);
    if (found != 0 && found != n)
      throw CsvError(path, 1,
                     "has only " + std::to_string(found) + " of the " + std::to_string(n) + " columns " + prefix +
                         "1…" + prefix + std::to_string(n) + suffix);
    return found == n;
  };
  if (!table.has("t")) throw CsvError(path, 1, "no column named 't'");
  if (!requireAllOrNone("y", Model::MeasDim, ""))
    throw CsvError(path, 1, "no columns y1…y" + std::to_string(Model::MeasDim));
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
  if (requireAllOrNone("x", Model::StateDim, "_true"))
    data.stateTruth = detail::readVectors<typename Model::State>(table, path, "x", "_true");
  data.parameterTruthFromFile = requireAllOrNone("theta", Model::ParamDim, "_true");
  if (data.parameterTruthFromFile)
    data.parameterTruth = detail::readVectors<typename Model::Param>(table, path, "theta", "_true");
  else
    data.parameterTruth.assign(table.rows(), fallbackTruth);
  return data;
}

/// Writes `data` as t, y1…ym, then x*_true when known, then theta*_true.
template <class Model>
void writePlantData(const std::string& path, const PlantData<Model>& data) {
  std::vector<std::string> header{"t"};
  for (const auto& names :
       {numberedNames("y", Model::MeasDim),
        data.stateTruth.empty() ? std::vector<std::string>{} : numberedNames("x", Model::StateDim, "_true"),
        numberedNames("theta", Model::ParamDim, "_true")})
    header.insert(header.end(), names.begin(), names.end());
  CsvWriter out(path, header);
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
