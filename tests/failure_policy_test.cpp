// The failure policy (design.md): a refused step returns a Status other than Ok and leaves the filter
// exactly as it was: estimate, covariance, parameters (and MJUKF's θᵢ), diagnostics, and the sigma
// points a following measurement update would use.

#include <limits>
#include <type_traits>

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include "mjukf/joint_ukf.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"
#include "robustness_support.hpp"

namespace {

using mjukf::Status;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// ẋ = θ x and y = x² + x₀ x, one of each. `blowUp` (shared through a pointer, since the filter
// keeps a copy of the model) makes the derivative or the measurement non-finite on demand.
struct ToyModel {
  using Scalar = double;
  static constexpr int StateDim = 1, ParamDim = 1, MeasDim = 1, InputDim = 1;
  using State = Eigen::Matrix<double, 1, 1>;
  using Param = State;
  using Meas = State;
  using Input = State;
  enum class BlowUp { Never, Derivative, Measurement };
  const BlowUp* blowUp = nullptr;
  double linearTerm = 0.0;

  Input input(double) const { return Input::Constant(1.0); }
  State derivative(double, const State& x, const Input& u, const Param& theta) const {
    if (blowUp && *blowUp == BlowUp::Derivative) return State::Constant(kNan);
    return State(theta(0) * x(0) + 0.1 * u(0));
  }
  Meas measurement(const State& x, const Param&) const {
    if (blowUp && *blowUp == BlowUp::Measurement) return Meas::Constant(kInf);
    return Meas(x(0) * x(0) + linearTerm * x(0));
  }
};

// Maps every point to zero: with Q = 0 the predicted covariance is then exactly 0, which has no
// Cholesky factor.
struct CollapsingStepper {
  using Scalar = double;
  [[maybe_unused]] static constexpr int order = 0, evaluationsPerStep = 0;  // the stepper convention
  template <class F, class State>
  State step(F&&, double, const State&, double) const {
    return State::Zero();
  }
};

// Everything a caller can observe of a filter.
template <class Filter>
struct Snapshot {
  typename Filter::State state;
  Eigen::MatrixXd covariance;
  typename Filter::Param parameters;
  Eigen::MatrixXd parameterPoints;
  typename Filter::Meas innovation;
  typename Filter::Meas::PlainObject innovationCovarianceDiagonal;
  double nis;
  bool hasPropagatedPoints;

  explicit Snapshot(const Filter& f)
      : state(f.state()), covariance(f.covariance()), parameters(f.parameters()),
        innovation(f.lastUpdate().innovation),
        innovationCovarianceDiagonal(f.lastUpdate().innovationCovariance.diagonal()), nis(f.lastUpdate().nis),
        hasPropagatedPoints(f.hasPropagatedPoints()) {
    if constexpr (std::is_same_v<Filter, mjukf::ModifiedJointUkf<typename Filter::Model, typename Filter::Integrator>>)
      parameterPoints = f.parameterPoints();
  }
  // Bitwise equality, NaN included (a refused step must not even touch a NaN).
  bool operator==(const Snapshot& o) const {
    using mjukf::testing::bitwiseSame;
    return bitwiseSame(state, o.state) && bitwiseSame(covariance, o.covariance) &&
           bitwiseSame(parameters, o.parameters) && bitwiseSame(parameterPoints, o.parameterPoints) && bitwiseSame(innovation, o.innovation) &&
           bitwiseSame(innovationCovarianceDiagonal, o.innovationCovarianceDiagonal) && nis == o.nis &&
           hasPropagatedPoints == o.hasPropagatedPoints;
  }
};

template <template <class, class> class FilterTemplate, class Stepper = mjukf::ITrBdf2<double>>
struct Toy {
  using Filter = FilterTemplate<ToyModel, Stepper>;
  // Settings valid for every filter; the sigma-point scaling and Q can be overridden.
  static Filter make(const ToyModel& model, mjukf::SigmaPointParameters<double> sigma = {}, double q = 1e-3,
                     double x0 = 0.5) {
    typename Filter::Settings s;
    s.sigmaPoints = sigma;
    s.initialCovariance.setIdentity();
    s.processNoise = q * decltype(s.processNoise)::Identity();
    s.measurementNoise.setConstant(1e-3);
    if constexpr (std::is_same_v<Filter, mjukf::ModifiedJointUkf<ToyModel, Stepper>>) {
      s.scaling = -0.1;
      s.transformation.setOnes();
      s.parameterSpread.setConstant(0.01);
    }
    return Filter(model, ToyModel::State(x0), ToyModel::Param(-0.5), s);
  }
};

template <class T>
class FailurePolicy : public ::testing::Test {};
template <template <class, class> class F>
struct Kind {
  template <class Stepper = mjukf::ITrBdf2<double>>
  using With = Toy<F, Stepper>;
};
using Kinds = ::testing::Types<Kind<mjukf::Ukf>, Kind<mjukf::JointUkf>, Kind<mjukf::ModifiedJointUkf>>;
TYPED_TEST_SUITE(FailurePolicy, Kinds);

// After a refused call, the next measurement update gives bit for bit what it gives on a filter that
// never saw the refused call: the stored sigma points survived too.
template <class Filter, class Refused>
void expectRefusedAndUnchanged(Filter& filter, Status expected, Refused&& refused) {
  const Snapshot<Filter> before(filter);
  Filter untouched = filter;
  EXPECT_EQ(refused(filter), expected);
  EXPECT_TRUE(Snapshot<Filter>(filter) == before) << "the refused call changed the filter";
  const typename Filter::Meas y(0.3);
  ASSERT_EQ(filter.measurementUpdate(y), Status::Ok);
  ASSERT_EQ(untouched.measurementUpdate(y), Status::Ok);
  EXPECT_TRUE(Snapshot<Filter>(filter) == Snapshot<Filter>(untouched)) << "the next update differs";
}

TYPED_TEST(FailurePolicy, NonFiniteMeasurementInEveryComponent) {
  auto filter = TypeParam::template With<>::make(ToyModel());
  ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  for (const double bad : {kNan, kInf, -kInf})
    expectRefusedAndUnchanged(filter, Status::NonFiniteMeasurement,
                              [&](auto& f) { return f.measurementUpdate(ToyModel::Meas(bad)); });
}

TYPED_TEST(FailurePolicy, InvalidStepSizes) {
  auto filter = TypeParam::template With<>::make(ToyModel());
  ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  for (const double h : {0.0, -0.01, kNan, kInf}) {
    expectRefusedAndUnchanged(filter, Status::InvalidStepSize, [&](auto& f) { return f.timeUpdate(0.0, h); });
    ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
    expectRefusedAndUnchanged(filter, Status::InvalidStepSize, [&](auto& f) { return f.propagateMean(0.0, h); });
    ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  }
  expectRefusedAndUnchanged(filter, Status::InvalidStepSize, [](auto& f) { return f.timeUpdate(kNan, 0.01); });
  ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  expectRefusedAndUnchanged(filter, Status::InvalidStepSize, [](auto& f) { return f.timeUpdate(0.0, 0.01, 0); });
}

TYPED_TEST(FailurePolicy, NonFiniteHeldInput) {
  auto filter = TypeParam::template With<>::make(ToyModel());
  ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  for (const double bad : {kNan, kInf, -kInf}) {
    expectRefusedAndUnchanged(filter, Status::NonFiniteInput,
                              [&](auto& f) { return f.timeUpdate(0.0, 0.01, ToyModel::Input(bad)); });
    ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
    expectRefusedAndUnchanged(filter, Status::NonFiniteInput,
                              [&](auto& f) { return f.propagateMean(0.0, 0.01, ToyModel::Input(bad)); });
    ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  }
}

TYPED_TEST(FailurePolicy, ModelReturnsNonFiniteValues) {
  ToyModel::BlowUp blowUp = ToyModel::BlowUp::Never;
  ToyModel model;
  model.blowUp = &blowUp;
  auto filter = TypeParam::template With<>::make(model);
  ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  const auto refuseWith = [&](ToyModel::BlowUp mode, auto call) {
    return [&blowUp, mode, call](auto& f) {
      blowUp = mode;
      const Status s = call(f);
      blowUp = ToyModel::BlowUp::Never;
      return s;
    };
  };
  expectRefusedAndUnchanged(filter, Status::NonFiniteResult,
                            refuseWith(ToyModel::BlowUp::Derivative, [](auto& f) { return f.timeUpdate(0.0, 0.01); }));
  ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  expectRefusedAndUnchanged(
      filter, Status::NonFiniteResult,
      refuseWith(ToyModel::BlowUp::Derivative, [](auto& f) { return f.propagateMean(0.0, 0.01); }));
  ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  expectRefusedAndUnchanged(filter, Status::NonFiniteResult,
                            refuseWith(ToyModel::BlowUp::Measurement,
                                       [](auto& f) { return f.measurementUpdate(ToyModel::Meas(0.3)); }));
}

TYPED_TEST(FailurePolicy, CovarianceWithoutCholeskyFactor) {
  // Q = 0 and a stepper that collapses every point: the time update would commit a P whose state row
  // is 0 (JUKF keeps the variance of θ), which has no Cholesky factor. With the repair off the time
  // update is refused and nothing changes.
  using Collapsing = typename TypeParam::template With<CollapsingStepper>;
  auto filter = Collapsing::make(ToyModel(), {}, 0.0);
  using Filter = decltype(filter);
  auto settings = filter.settings();
  settings.repair.maxAttempts = 0;
  Filter strict(filter.model(), filter.state(), filter.parameters(), settings);
  const Snapshot<Filter> before(strict);
  EXPECT_EQ(strict.timeUpdate(0.0, 0.01), Status::NotPositiveDefinite);
  EXPECT_TRUE(Snapshot<Filter>(strict) == before);
  // With the default repair, the UKF's and MJUKF's P⁻ = 0 (1 × 1) has no scale to repair against and
  // is refused too; JUKF's singular P⁻ gets a jitter of 16ε × mean|Pᵢᵢ| and the step is taken.
  const Snapshot<Filter> defaults(filter);
  const Status status = filter.timeUpdate(0.0, 0.01);
  if constexpr (std::is_same_v<Filter, mjukf::JointUkf<ToyModel, CollapsingStepper>>) {
    ASSERT_EQ(status, Status::Repaired);
    EXPECT_GT(filter.covariance()(0, 0), 0.0);
    EXPECT_LE(filter.covariance()(0, 0), 16 * 2.3e-16 * 1e4 * filter.covariance().diagonal().mean());
    EXPECT_EQ(filter.covariance().llt().info(), Eigen::Success);
  } else {
    EXPECT_EQ(status, Status::NotPositiveDefinite);
    EXPECT_TRUE(Snapshot<Filter>(filter) == defaults);
  }
}

TYPED_TEST(FailurePolicy, InnovationCovarianceWithoutCholeskyFactor) {
  // α = 0.1, β = −1 makes the central covariance weight Wc₀ ≈ −99: around x̂ = 0 the images of
  // y = x² give Σ Wcᵢ (Yᵢ − ŷ)² ≈ −1, which R = 1e-3 cannot make positive.
  auto filter = TypeParam::template With<>::make(ToyModel(), {0.1, -1.0, 0.0}, 1e-3, 0.0);
  const Snapshot<decltype(filter)> before(filter);
  EXPECT_EQ(filter.measurementUpdate(ToyModel::Meas(0.3)), Status::InnovationNotPositiveDefinite);
  EXPECT_TRUE(Snapshot<decltype(filter)>(filter) == before);
}

}  // namespace
