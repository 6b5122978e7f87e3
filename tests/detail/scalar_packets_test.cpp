// detail/linear_algebra.hpp where Eigen has no vector unit (a packet is one coefficient, as on the
// Cortex-M4F of the firmware), built here with EIGEN_DONT_VECTORIZE: the kernels chosen for that case
// give the bits of the forms they replace.

#include <cstring>
#include <random>

#include <gtest/gtest.h>

#include "mjukf/detail/linear_algebra.hpp"
#include "random_matrix.hpp"

namespace {

using mjukf::testing::randomNormal;

static_assert(mjukf::detail::kScalarPackets<float> && mjukf::detail::kScalarPackets<double>,
              "this test is built without Eigen's vectorisation");

// The lower triangle of Σ Wcᵢ dᵢ dᵢᵀ by the kernel weightedCovarianceLower chooses for a point set of
// L = Count / 2 below the general kernels' sizes, and by the coefficient-wise form that holds d W,
// compared as bytes. From kLazyWeightingFrom on the former weights d again in each column's product;
// below (L = 4 here), the two are one form.
template <class Scalar, int N, int Count>
void expectChosenCovarianceIsTheHeldOne(std::mt19937_64& rng) {
  const auto d = randomNormal<Eigen::Matrix<Scalar, N, Count>>(rng);
  const auto w = randomNormal<Eigen::Matrix<Scalar, Count, 1>>(rng);
  Eigen::Matrix<Scalar, N, N> held = Eigen::Matrix<Scalar, N, N>::Zero(), chosen = held;
  mjukf::detail::weightedCovarianceLowerCoefficientwise(d, w, held);
  mjukf::detail::weightedCovarianceLower(d, w, chosen);
  for (int j = 0; j < N; ++j)
    for (int i = j; i < N; ++i)
      EXPECT_EQ(std::memcmp(&chosen(i, j), &held(i, j), sizeof(Scalar)), 0)
          << N << " x " << Count << " at " << i << ", " << j;
  EXPECT_TRUE((chosen.template triangularView<Eigen::StrictlyUpper>().toDenseMatrix().array() == 0).all());
}

template <class Scalar, int L>
void expectChosenCovariancesAreTheHeldOnes(std::mt19937_64& rng) {
  expectChosenCovarianceIsTheHeldOne<Scalar, L, 2 * L + 1>(rng);  // P⁻ of a joint filter
  expectChosenCovarianceIsTheHeldOne<Scalar, 4, 2 * L + 1>(rng);  // P_yy of four measurements
}

TEST(ScalarPackets, CovarianceKernelChosenBySizeHasTheHeldFormsBits) {
  std::mt19937_64 rng(21);
  expectChosenCovariancesAreTheHeldOnes<float, 4>(rng);
  expectChosenCovariancesAreTheHeldOnes<float, 6>(rng);  // the robot's JUKF
  expectChosenCovariancesAreTheHeldOnes<float, 7>(rng);
  expectChosenCovariancesAreTheHeldOnes<float, 8>(rng);
  expectChosenCovariancesAreTheHeldOnes<double, 6>(rng);
  expectChosenCovariancesAreTheHeldOnes<double, 8>(rng);
}

// Where packets are one coefficient, deviationsFrom is Eigen's expression; in place (the dual UKF's
// measurement deviations) it gives what colwise() −= gives, byte for byte.
TEST(ScalarPackets, DeviationsInPlaceAreColwiseSubtraction) {
  std::mt19937_64 rng(23);
  auto points = randomNormal<Eigen::Matrix<float, 4, 9>>(rng);
  const auto centre = randomNormal<Eigen::Matrix<float, 4, 1>>(rng);
  Eigen::Matrix<float, 4, 9> expected = points;
  expected.colwise() -= centre;
  mjukf::detail::deviationsFrom(points, centre, points);
  EXPECT_EQ(std::memcmp(points.data(), expected.data(), sizeof(points)), 0);
}

}  // namespace
