#pragma once

/// \file
/// The accuracy metric of the paper's experiments: the RMSE of the parameter estimates (eq. 16;
/// docs/algorithms.md §8).

#include <Eigen/Core>

namespace mjukf::paper {

/// Root-mean-square error of a parameter vector against its truth, accumulated row by row (eq. 16).
/// The squares are summed in double even for float estimates: a float sum over the tank's 180 000 rows
/// would lose about 1% to rounding.
template <class Scalar, int Dim>
class RmseAccumulator {
 public:
  /// A vector of the Dim quantities.
  using Vector = Eigen::Matrix<Scalar, Dim, 1>;

  /// Adds one row: the squared error of each component.
  void add(const Vector& estimate, const Vector& truth) {
    sumOfSquares_ += (estimate - truth).template cast<double>().array().square().matrix();
    ++count_;
  }
  /// The RMSE of each component over the rows added so far (NaN before the first row).
  Vector value() const { return (sumOfSquares_ / double(count_)).array().sqrt().matrix().template cast<Scalar>(); }
  /// The number of rows added.
  long count() const { return count_; }

 private:
  Eigen::Matrix<double, Dim, 1> sumOfSquares_ = Eigen::Matrix<double, Dim, 1>::Zero();
  long count_ = 0;
};

}  // namespace mjukf::paper
