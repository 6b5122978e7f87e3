#pragma once

// Helpers of the hardening tests: bitwise snapshots of a filter, a simulated coupled tank with noise,
// and the check every committed covariance must pass.

#include <cstring>
#include <random>
#include <type_traits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mjukf/dual_ukf.hpp"
#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/simulation.hpp"
#include "mjukf/ukf.hpp"

namespace mjukf::testing {

template <class A, class B>
bool bitwiseSame(const A& a, const B& b) {
  using Scalar = typename A::Scalar;
  if (a.size() != b.size()) return false;
  // A model without parameters has empty vectors, whose null data() memcmp may not get.
  return a.size() == 0 || std::memcmp(a.data(), b.data(), sizeof(Scalar) * std::size_t(a.size())) == 0;
}

// Which filter a type is, whatever its stepper, sigma-point set and covariance form.
template <class T>
struct IsModifiedJoint : std::false_type {};
template <class M, class I, class P, class F>
struct IsModifiedJoint<ModifiedJointUkf<M, I, P, F>> : std::true_type {};
template <class T>
struct IsDual : std::false_type {};
template <class M, class I, class P, class F>
struct IsDual<DualUkf<M, I, P, F>> : std::true_type {};
template <class T>
struct IsJoint : std::false_type {};
template <class M, class I, class P, class F>
struct IsJoint<JointUkf<M, I, P, F>> : std::true_type {};
template <class T>
struct IsUkf : std::false_type {};
template <class M, class I, class P, class F>
struct IsUkf<Ukf<M, I, P, F>> : std::true_type {};

/// Success when everything a caller can observe of the two filters is bit for bit the same, NaN
/// included; otherwise a failure naming what differs. The filters may be of different types with the
/// same accessors (a continuous model and its discrete twin); A decides which accessors are compared.
template <class A, class B>
::testing::AssertionResult sameFilter(const A& a, const B& b) {
  const auto differ = [](const char* what) { return ::testing::AssertionFailure() << what << " differs"; };
  const auto sameScalar = [](auto x, auto y) { return std::memcmp(&x, &y, sizeof x) == 0; };
  if (!bitwiseSame(a.state(), b.state())) return differ("state");
  if (!bitwiseSame(a.covariance(), b.covariance())) return differ("covariance");
  if (!bitwiseSame(a.parameters(), b.parameters())) return differ("parameters");
  if (!bitwiseSame(a.lastUpdate().innovation, b.lastUpdate().innovation)) return differ("innovation");
  if (!bitwiseSame(a.lastUpdate().innovationCovariance, b.lastUpdate().innovationCovariance))
    return differ("innovation covariance");
  if (!sameScalar(a.lastUpdate().nis, b.lastUpdate().nis)) return differ("NIS");
  if (a.hasPropagatedPoints() != b.hasPropagatedPoints()) return differ("hasPropagatedPoints");
  if constexpr (IsModifiedJoint<A>::value) {
    if (!bitwiseSame(a.parameterPoints(), b.parameterPoints())) return differ("parameterPoints");
    if (!bitwiseSame(a.transformation(), b.transformation())) return differ("transformation");
    if (!bitwiseSame(a.scalings(), b.scalings())) return differ("scalings");
    if (!bitwiseSame(a.sensitivity().stateSensitivity(), b.sensitivity().stateSensitivity()))
      return differ("state sensitivity");
    if (!bitwiseSame(a.sensitivity().measurementSensitivity(), b.sensitivity().measurementSensitivity()))
      return differ("measurement sensitivity");
    if (!bitwiseSame(a.sensitivity().information(), b.sensitivity().information())) return differ("information");
  }
  if constexpr (IsDual<A>::value) {
    if (!bitwiseSame(a.parameterCovariance(), b.parameterCovariance())) return differ("parameterCovariance");
    if (!bitwiseSame(a.lastParameterUpdate().innovation, b.lastParameterUpdate().innovation))
      return differ("parameter innovation");
    if (!bitwiseSame(a.lastParameterUpdate().innovationCovariance, b.lastParameterUpdate().innovationCovariance))
      return differ("parameter innovation covariance");
    if (!sameScalar(a.lastParameterUpdate().nis, b.lastParameterUpdate().nis)) return differ("parameter NIS");
  }
  return ::testing::AssertionSuccess();
}

/// Exactly symmetric (P == Pᵀ bit for bit, as every commit symmetrises) and with a Cholesky factor.
template <class Matrix>
bool symmetricPositiveDefinite(const Matrix& p) {
  if (!p.allFinite() || !(p.array() == p.transpose().array()).all()) return false;
  return Eigen::LLT<typename Matrix::PlainObject>(p).info() == Eigen::Success;
}

/// The coupled tank simulated with I-TR-BDF2 at step h from rest, true k_flow, and white Gaussian noise
/// of standard deviation `sigma` on both levels; rows generated on demand so that runs of any length
/// need no storage. Call next() once per row, in order.
template <class Model>
class TankMeasurements {
 public:
  using State = typename Model::State;
  using Meas = typename Model::Meas;

  TankMeasurements(double h, double sigma, unsigned long long seed) : h_(h), sigma_(sigma), random_(seed) {
    truth_.setZero();
  }

  /// The measurement of row k + 1 after the one of row k (row 0 is the initial state).
  const Meas& next() {
    const auto theta = Model::trueParameters();
    if (row_ > 0) truth_ = stepModel(model_, integrator_, double(row_ - 1) * h_, h_, truth_, theta);
    ++row_;
    y_ = model_.measurement(truth_, theta);
    for (int c = 0; c < Model::MeasDim; ++c) y_(c) += sigma_ * noise_(random_);
    return y_;
  }
  /// The measurement of row k ≥ the last row asked for (rows in between are generated and dropped).
  const Meas& at(long k) {
    while (row_ <= k) next();
    return y_;
  }
  long row() const { return row_ - 1; }
  const State& truth() const { return truth_; }

 private:
  Model model_;
  ITrBdf2<double> integrator_;
  double h_, sigma_;
  std::mt19937_64 random_;
  std::normal_distribution<double> noise_{0.0, 1.0};
  State truth_;
  Meas y_;
  long row_ = 0;
};

}  // namespace mjukf::testing
