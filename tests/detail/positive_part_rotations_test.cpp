// MJUKF_POSITIVE_PART_BY_ROTATIONS (defined for this target by CMake, before any header): the positive
// part of the MJUKF's floor keeps the Jacobi rotations at every size, so that a firmware image of an
// automatic MJUKF with five states or more does not link Eigen's eigensolver and its malloc
// (docs/embedded.md). The dispatch then takes the rotations' code, bit for bit, at sizes where it would
// otherwise take the solver.

#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "mjukf/detail/linear_algebra.hpp"
#include "test_support.hpp"

#ifndef MJUKF_POSITIVE_PART_BY_ROTATIONS
#error "this test is built with MJUKF_POSITIVE_PART_BY_ROTATIONS"
#endif

namespace {

template <int N>
void expectRotations(std::mt19937_64& rng) {
  using Matrix = Eigen::Matrix<double, N, N>;
  const Matrix a = mjukf::testing::randomSymmetric<N>(rng);
  Matrix dispatched, byRotations;
  ASSERT_TRUE(mjukf::detail::positivePartFactor(a, dispatched));
  ASSERT_TRUE(mjukf::detail::positivePartFactorJacobi(a, byRotations));
  EXPECT_TRUE(dispatched == byRotations) << "N = " << N;
}

TEST(PositivePartByRotations, EverySizeTakesTheRotations) {
  static_assert(mjukf::detail::kTridiagonalPositivePartFrom == std::numeric_limits<int>::max());
  std::mt19937_64 rng(29);
  expectRotations<5>(rng);
  expectRotations<8>(rng);
  expectRotations<20>(rng);
}

}  // namespace
