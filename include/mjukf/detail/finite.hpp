#pragma once

// The finiteness check of the per-step path.

#include <Eigen/Core>

namespace mjukf::detail {

// True when no coefficient is NaN or ±Inf. Eigen's allFinite() compares x − x with itself and stops
// at the first mismatch: a branch per coefficient, which on a step's few dozen values costs more than
// the arithmetic it guards. Here x·0 is 0 for a finite x and NaN otherwise, and a sum is NaN as soon
// as one of its terms is, so the check is one vectorised reduction. (Like Eigen's, it needs IEEE
// arithmetic: -ffinite-math-only would let a compiler fold it to true.)
template <class Derived>
bool allFinite(const Eigen::DenseBase<Derived>& m) {
  using Scalar = typename Derived::Scalar;
  return (m.derived().array() * Scalar(0)).sum() == Scalar(0);
}

}  // namespace mjukf::detail
