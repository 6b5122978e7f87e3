#pragma once

// Random fixed-size matrices for the tests, in a header of its own that includes Eigen's core alone, for
// the tests that do not need the filters of test_support.hpp (which includes every filter header).

#include <random>

#include <Eigen/Core>

namespace mjukf::testing {

/// A fixed-size matrix of independent normal entries of standard deviation `sd`, drawn in double row by
/// row and rounded to the matrix's scalar type.
template <class Matrix>
Matrix randomNormal(std::mt19937_64& rng, double sd = 1.0) {
  using Scalar = typename Matrix::Scalar;
  std::normal_distribution<double> normal(0.0, sd);
  Matrix m;
  for (int i = 0; i < m.rows(); ++i)
    for (int j = 0; j < m.cols(); ++j) m(i, j) = Scalar(normal(rng));
  return m;
}

}  // namespace mjukf::testing
