// libFuzzer target: arbitrary settings, initial values, measurements, masks, inputs, times and step
// sizes fed to the three filters on both plants of the paper. A constructor may throw
// std::invalid_argument (a refused setting); every per-step call must return a Status, and then:
//   taken   → the estimate is finite and the covariance exactly symmetric with a Cholesky factor;
//   refused → the filter is bit for bit what it was before the call.
// Anything else traps, and ASan/UBSan report memory errors and undefined behaviour.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include <Eigen/Eigenvalues>
#include <fuzzer/FuzzedDataProvider.h>

#include "mjukf/joint_ukf.hpp"
#include "mjukf/models/coupled_tank.hpp"
#include "mjukf/models/flexible_joint.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"

namespace {

// A double: often one that is known to hurt (NaN, ±Inf, 0, huge, tiny), else ordinary or raw bits.
double value(FuzzedDataProvider& in) {
  static constexpr double special[] = {0.0,
                                       -0.0,
                                       1.0,
                                       -1.0,
                                       0.5,
                                       1e-3,
                                       1e-7,
                                       1e-300,
                                       -1e-300,
                                       1e300,
                                       -1e300,
                                       std::numeric_limits<double>::quiet_NaN(),
                                       std::numeric_limits<double>::infinity(),
                                       -std::numeric_limits<double>::infinity(),
                                       std::numeric_limits<double>::denorm_min(),
                                       std::numeric_limits<double>::max(),
                                       std::numeric_limits<double>::epsilon()};
  switch (in.ConsumeIntegralInRange(0, 3)) {
    case 0: return special[in.ConsumeIntegralInRange<std::size_t>(0, std::size(special) - 1)];
    case 1: return in.ConsumeFloatingPointInRange(-10.0, 10.0);
    case 2: return in.ConsumeFloatingPoint<double>();
    default: return in.ConsumeProbability<double>() * std::pow(10.0, in.ConsumeIntegralInRange(-9, 9));
  }
}

template <class M>
void fill(FuzzedDataProvider& in, M& m) {
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = value(in);
}

// A covariance: usually a positive diagonal (so that construction succeeds and the steps run),
// sometimes anything at all.
template <class M>
void covariance(FuzzedDataProvider& in, M& m) {
  m.setZero();
  if (in.ConsumeBool()) {
    fill(in, m);
    return;
  }
  for (Eigen::Index i = 0; i < m.rows(); ++i) m(i, i) = std::abs(value(in));
  if (in.ConsumeBool()) {  // a correlation between two entries, kept symmetric
    const auto r = in.ConsumeIntegralInRange<Eigen::Index>(0, m.rows() - 1);
    const auto c = in.ConsumeIntegralInRange<Eigen::Index>(0, m.rows() - 1);
    m(r, c) = m(c, r) = value(in);
  }
}

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "mjukf_fuzz: %s\n", what);
  __builtin_trap();
}

template <class A>
bool same(const A& a, const A& b) {
  return std::memcmp(a.data(), b.data(), sizeof(typename A::Scalar) * std::size_t(a.size())) == 0;
}

template <class Filter>
bool unchanged(const Filter& a, const Filter& b) {
  bool s = same(a.state(), b.state()) && same(a.covariance(), b.covariance()) && same(a.parameters(), b.parameters()) &&
           same(a.lastUpdate().innovation, b.lastUpdate().innovation) &&
           same(a.lastUpdate().innovationCovariance, b.lastUpdate().innovationCovariance) &&
           std::memcmp(&a.lastUpdate().nis, &b.lastUpdate().nis, sizeof(double)) == 0 &&
           a.hasPropagatedPoints() == b.hasPropagatedPoints();
  if constexpr (std::is_same_v<Filter, mjukf::ModifiedJointUkf<typename Filter::Model>>)
    s = s && same(a.parameterPoints(), b.parameterPoints());
  return s;
}

template <class Filter>
void check(const Filter& after, const Filter& before, mjukf::Status status) {
  using mjukf::Status;
  switch (status) {
    case Status::Ok:
    case Status::Repaired: {
      const auto& p = after.covariance();
      if (!after.state().allFinite() || !after.parameters().allFinite() || !p.allFinite())
        fail("a taken step left a non-finite estimate or covariance");
      if (!(p.array() == p.transpose().array()).all()) fail("a taken step left a covariance that is not symmetric");
      // The library's promise: P has the Cholesky factor its next draw needs (its own factorisation,
      // with the pivot margin of detail/linear_algebra.hpp) ...
      typename std::decay_t<decltype(p)>::PlainObject factor;
      if (!mjukf::detail::choleskyLower(p, factor)) fail("a taken step left a covariance without a Cholesky factor");
      // ... and, checked independently, P is positive semi-definite to within rounding. Not Eigen's LLT
      // on P: for a P with a condition number near 1/ε, definiteness is decided by rounding, and two
      // correct factorisations that sum in different orders can disagree (the fuzzer found such a P,
      // eigenvalues from -1.1e7 to 8.5e25).
      const Eigen::SelfAdjointEigenSolver<typename std::decay_t<decltype(p)>::PlainObject> eigen(
          p, Eigen::EigenvaluesOnly);
      const double largest = eigen.eigenvalues().cwiseAbs().maxCoeff();
      if (eigen.eigenvalues().minCoeff() < -10.0 * double(p.rows()) * std::numeric_limits<double>::epsilon() * largest)
        fail("a taken step left an indefinite covariance");
      return;
    }
    case Status::NonFiniteMeasurement:
    case Status::NonFiniteInput:
    case Status::InvalidStepSize:
    case Status::NotPositiveDefinite:
    case Status::InnovationNotPositiveDefinite:
    case Status::NonFiniteResult:
    case Status::MeasurementRejected:
    case Status::StepTooLarge:
      if (!unchanged(after, before)) fail("a refused call changed the filter");
      return;
  }
  fail("not a Status value");
}

template <class Filter>
void drive(FuzzedDataProvider& in, Filter& filter) {
  using Meas = typename Filter::Meas;
  using Input = typename Filter::Input;
  for (int call = 0; call < 64 && in.remaining_bytes() > 0; ++call) {
    const Filter before = filter;
    mjukf::Status status;
    const double t = value(in), h = in.ConsumeBool() ? 1e-3 * in.ConsumeProbability<double>() + 1e-6 : value(in);
    const int steps = in.ConsumeIntegralInRange(-1, 3);
    switch (in.ConsumeIntegralInRange(0, 5)) {
      case 0: status = filter.timeUpdate(t, h, steps); break;
      case 1: {
        Input u;
        fill(in, u);
        status = filter.timeUpdate(t, h, u, steps);
        break;
      }
      case 2: status = filter.propagateMean(t, h, steps); break;
      case 3: {
        Meas y = filter.model().measurement(before.state(), before.parameters());
        for (int j = 0; j < Meas::RowsAtCompileTime; ++j)
          if (in.ConsumeBool()) y(j) = in.ConsumeBool() ? value(in) : y(j) + in.ConsumeFloatingPointInRange(-1.0, 1.0);
        status = filter.measurementUpdate(y);
        break;
      }
      case 4: {
        Meas y;
        fill(in, y);
        mjukf::MeasurementMask<Meas::RowsAtCompileTime> present;
        for (int j = 0; j < Meas::RowsAtCompileTime; ++j) present(j) = in.ConsumeBool();
        status = filter.measurementUpdate(y, present);
        break;
      }
      default: {
        Input u;
        fill(in, u);
        status = filter.propagateMean(t, h, u, steps);
        break;
      }
    }
    check(filter, before, status);
  }
}

template <template <class...> class F, class Model>
void run(FuzzedDataProvider& in) {
  using Filter = F<Model, mjukf::ITrBdf2<double>>;
  typename Filter::Settings s;
  s.sigmaPoints = {in.ConsumeBool() ? 1.0 : value(in), in.ConsumeBool() ? 2.0 : value(in),
                   in.ConsumeBool() ? 0.0 : value(in)};
  covariance(in, s.initialCovariance);
  covariance(in, s.processNoise);
  covariance(in, s.measurementNoise);
  s.redrawPointsForUpdate = in.ConsumeBool();
  s.repair.maxAttempts = in.ConsumeIntegralInRange(-1, 6);
  if (in.ConsumeBool()) s.repair.firstJitter = value(in);
  if (in.ConsumeBool()) s.repair.growth = value(in);
  if (in.ConsumeBool()) fill(in, s.gate.nisThreshold);
  typename Model::State x0;
  typename Model::Param theta0 = Model::trueParameters();
  fill(in, x0);
  if (in.ConsumeBool()) fill(in, theta0);
  if constexpr (!std::is_same_v<Filter, mjukf::Ukf<Model, mjukf::ITrBdf2<double>>>) {
    if (in.ConsumeBool()) fill(in, s.parameterBounds.lower);
    if (in.ConsumeBool()) fill(in, s.parameterBounds.upper);
  }
  if constexpr (std::is_same_v<Filter, mjukf::ModifiedJointUkf<Model, mjukf::ITrBdf2<double>>>) {
    s.scaling = value(in);
    s.transformation.setConstant(1.0 / Model::MeasDim);  // rows sum to 1 …
    if (in.ConsumeBool()) fill(in, s.transformation);    // … or anything
    fill(in, s.parameterSpread);
  }
  try {
    Filter filter(Model(), x0, theta0, s);
    drive(in, filter);
  } catch (const std::invalid_argument&) {
    // A refused setting: a valid outcome of construction.
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  using Tank = mjukf::models::CoupledTank<double>;
  using Robot = mjukf::models::FlexibleJoint<double>;
  switch (in.ConsumeIntegralInRange(0, 5)) {
    case 0: run<mjukf::Ukf, Tank>(in); break;
    case 1: run<mjukf::JointUkf, Tank>(in); break;
    case 2: run<mjukf::ModifiedJointUkf, Tank>(in); break;
    case 3: run<mjukf::Ukf, Robot>(in); break;
    case 4: run<mjukf::JointUkf, Robot>(in); break;
    default: run<mjukf::ModifiedJointUkf, Robot>(in); break;
  }
  return 0;
}
