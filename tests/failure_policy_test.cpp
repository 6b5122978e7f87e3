// The failure policy (docs/design.md): a refused step returns a Status other than Ok and leaves
// the filter exactly as it was: estimate, covariance, parameters (and MJUKF's θᵢ), diagnostics, and the sigma
// points a following measurement update would use. The dual filter's parameter filter too: θ̂, P^θ,
// its diagnostics, and the prior its UpdatedParameters ordering runs the time update again from. Every
// filter in both covariance forms (covariance_form.hpp): the square-root form's refusals are the full
// form's.

#include <cmath>
#include <limits>
#include <type_traits>

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include "mjukf/dual_ukf.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/measurement_gating.hpp"
#include "mjukf/models/coupled_tank.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"
#include "paper/experiments.hpp"
#include "robustness_support.hpp"
#include "test_support.hpp"

namespace {

using mjukf::testing::IsDual;
using mjukf::testing::IsJoint;
using mjukf::testing::IsModifiedJoint;
using mjukf::testing::SquareRoot;

using mjukf::Status;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// ẋ = θ x and y = x² + x₀ x, one of each. `blowUp` (shared through a pointer, since the filter
// keeps a copy of the model) makes the derivative or the measurement non-finite on demand; LargeState
// makes the derivative NaN only where |x| > 1.2, which the sigma points about x̂ = 0.5 with P ≈ 1 reach
// (x̂ ± γ√P, γ = √(L + λ) ≥ 1) and the mean does not.
template <class Scalar_>
struct BasicToyModel {
  using Scalar = Scalar_;
  static constexpr int StateDim = 1, ParamDim = 1, MeasDim = 1, InputDim = 1;
  using State = Eigen::Matrix<Scalar, 1, 1>;
  using Param = State;
  using Meas = State;
  using Input = State;
  enum class BlowUp { Never, Derivative, Measurement, LargeState };
  const BlowUp* blowUp = nullptr;
  Scalar linearTerm = 0;

  Input input(Scalar) const { return Input::Constant(Scalar(1)); }
  State derivative(Scalar, const State& x, const Input& u, const Param& theta) const {
    if (blowUp && (*blowUp == BlowUp::Derivative || (*blowUp == BlowUp::LargeState && std::abs(x(0)) > Scalar(1.2))))
      return State::Constant(std::numeric_limits<Scalar>::quiet_NaN());
    return State(theta(0) * x(0) + Scalar(0.1) * u(0));
  }
  Meas measurement(const State& x, const Param&) const {
    if (blowUp && *blowUp == BlowUp::Measurement) return Meas::Constant(std::numeric_limits<Scalar>::infinity());
    return Meas(x(0) * x(0) + linearTerm * x(0));
  }
};
using ToyModel = BasicToyModel<double>;

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
  using Scalar = typename Filter::Scalar;
  using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  typename Filter::State state;
  Matrix covariance;
  typename Filter::Param parameters;
  Matrix parameterPoints;
  Matrix automaticState;  // MJUKF: T, ξ, W, ψ and the information of the automatic modes, side by side
  typename Filter::Meas innovation;
  typename Filter::Meas::PlainObject innovationCovarianceDiagonal;
  Scalar nis;
  bool hasPropagatedPoints;
  // The dual filter's parameter filter, and the MJUKF's P_θ and detected changes (empty for the others).
  Matrix parameterCovariance;
  long detectedChanges = 0;
  Matrix parameterInnovation;
  Matrix parameterInnovationCovariance;
  Matrix parameterNis;

  explicit Snapshot(const Filter& f)
      : state(f.state()),
        covariance(f.covariance()),
        parameters(f.parameters()),
        innovation(f.lastUpdate().innovation),
        innovationCovarianceDiagonal(f.lastUpdate().innovationCovariance.diagonal()),
        nis(f.lastUpdate().nis),
        hasPropagatedPoints(f.hasPropagatedPoints()) {
    if constexpr (IsModifiedJoint<Filter>::value) {
      parameterPoints = f.parameterPoints();
      const auto& k = f.sensitivity();
      automaticState.resize(f.transformation().rows(), f.transformation().cols() + 1 + k.stateSensitivity().rows() +
                                                           k.measurementSensitivity().rows() + k.information().cols());
      automaticState << f.transformation(), f.scalings(), k.stateSensitivity().transpose(),
          k.measurementSensitivity().transpose(), k.information();
      const auto pt = f.parameterCovariance();           // copied by coefficient: g++ 12 warns (-Warray-bounds,
      parameterCovariance.resize(pt.rows(), pt.cols());  // a false positive) on Eigen's packet copy of 1 × 1
      for (Eigen::Index i = 0; i < pt.rows(); ++i)
        for (Eigen::Index j = 0; j < pt.cols(); ++j) parameterCovariance(i, j) = pt(i, j);
      detectedChanges = f.detectedParameterChanges();
    }
    if constexpr (IsDual<Filter>::value) {
      parameterCovariance = f.parameterCovariance();
      parameterInnovation = f.lastParameterUpdate().innovation;
      parameterInnovationCovariance = f.lastParameterUpdate().innovationCovariance;
      parameterNis = Matrix::Constant(1, 1, f.lastParameterUpdate().nis);
    }
  }
  // Bitwise equality, NaN included (a refused step must not even touch a NaN).
  bool operator==(const Snapshot& o) const {
    using mjukf::testing::bitwiseSame;
    return bitwiseSame(state, o.state) && bitwiseSame(covariance, o.covariance) &&
           bitwiseSame(parameters, o.parameters) && bitwiseSame(parameterPoints, o.parameterPoints) &&
           bitwiseSame(automaticState, o.automaticState) && bitwiseSame(innovation, o.innovation) &&
           bitwiseSame(innovationCovarianceDiagonal, o.innovationCovarianceDiagonal) && nis == o.nis &&
           hasPropagatedPoints == o.hasPropagatedPoints && bitwiseSame(parameterCovariance, o.parameterCovariance) &&
           detectedChanges == o.detectedChanges && bitwiseSame(parameterInnovation, o.parameterInnovation) &&
           bitwiseSame(parameterInnovationCovariance, o.parameterInnovationCovariance) &&
           bitwiseSame(parameterNis, o.parameterNis);
  }
};

template <template <class...> class FilterTemplate, class Stepper = mjukf::ITrBdf2<double>,
          mjukf::DualUkfOrdering Ordering = mjukf::DualUkfOrdering::PriorParameters, class Model = ToyModel,
          bool AutomaticMjukf = false>
struct Toy {
  using Filter = FilterTemplate<Model, Stepper>;
  using Scalar = typename Model::Scalar;
  // Settings valid for every filter; the sigma-point scaling and Q can be overridden.
  static Filter make(const Model& model, mjukf::SigmaPointParameters<Scalar> sigma = {}, Scalar q = Scalar(1e-3),
                     Scalar x0 = Scalar(0.5)) {
    typename Filter::Settings s;
    s.sigmaPoints = sigma;
    s.initialCovariance.setIdentity();
    s.processNoise = q * decltype(s.processNoise)::Identity();
    s.measurementNoise.setConstant(Scalar(1e-3));
    if constexpr (IsModifiedJoint<Filter>::value) {
      s.scaling = Scalar(-0.1);
      s.transformation.setOnes();
      s.parameterSpread.setConstant(Scalar(0.01));
      s.automaticTransformation = s.adaptiveScaling = AutomaticMjukf;
    }
    if constexpr (IsDual<Filter>::value) {
      s.initialParameterCovariance.setConstant(Scalar(0.1));
      s.parameterProcessNoise.setConstant(Scalar(1e-4));
      s.parameterObservationNoise.setConstant(Scalar(1e-3));
      s.ordering = Ordering;
    }
    return Filter(model, typename Model::State(x0), typename Model::Param(Scalar(-0.5)), s);
  }
};

template <class T>
class FailurePolicy : public ::testing::Test {};
template <template <class...> class F>
struct Kind {
  template <class Stepper = mjukf::ITrBdf2<double>>
  using With = Toy<F, Stepper>;
};
template <mjukf::DualUkfOrdering Ordering, template <class...> class F = mjukf::DualUkf>
struct DualKind {
  template <class Stepper = mjukf::ITrBdf2<double>>
  using With = Toy<F, Stepper, Ordering>;
};
// MJUKF with both automatic modes (T from the sensitivities, adaptive ξ).
template <template <class...> class F = mjukf::ModifiedJointUkf>
struct AutomaticMjukfKind {
  template <class Stepper = mjukf::ITrBdf2<double>>
  using With = Toy<F, Stepper, mjukf::DualUkfOrdering::PriorParameters, ToyModel, true>;
};
using Kinds = ::testing::Types<
    Kind<mjukf::Ukf>, Kind<mjukf::JointUkf>, Kind<mjukf::ModifiedJointUkf>, AutomaticMjukfKind<>,
    DualKind<mjukf::DualUkfOrdering::PriorParameters>, DualKind<mjukf::DualUkfOrdering::UpdatedParameters>,
    // The square-root form.
    Kind<SquareRoot<mjukf::Ukf>::Filter>, Kind<SquareRoot<mjukf::JointUkf>::Filter>,
    Kind<SquareRoot<mjukf::ModifiedJointUkf>::Filter>, AutomaticMjukfKind<SquareRoot<mjukf::ModifiedJointUkf>::Filter>,
    DualKind<mjukf::DualUkfOrdering::PriorParameters, SquareRoot<mjukf::DualUkf>::Filter>,
    DualKind<mjukf::DualUkfOrdering::UpdatedParameters, SquareRoot<mjukf::DualUkf>::Filter>>;
TYPED_TEST_SUITE(FailurePolicy, Kinds);

// After a refused call, the next measurement update gives bit for bit what it gives on a filter that
// never saw the refused call: the stored sigma points survived too.
template <class Filter, class Refused>
void expectRefusedAndUnchanged(Filter& filter, Status expected, Refused&& refused) {
  const Snapshot<Filter> before(filter);
  Filter untouched = filter;
  EXPECT_EQ(refused(filter), expected);
  EXPECT_TRUE(Snapshot<Filter>(filter) == before) << "the refused call changed the filter";
  const typename Filter::Meas y(typename Filter::Scalar(0.3));
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
  expectRefusedAndUnchanged(filter, Status::NonFiniteResult, refuseWith(ToyModel::BlowUp::Derivative, [](auto& f) {
                              return f.propagateMean(0.0, 0.01);
                            }));
  ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  expectRefusedAndUnchanged(filter, Status::NonFiniteResult, refuseWith(ToyModel::BlowUp::Measurement, [](auto& f) {
                              return f.measurementUpdate(ToyModel::Meas(0.3));
                            }));
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
  // With the default repair, the UKF's, MJUKF's and the dual filter's state P⁻ = 0 (1 × 1) has no
  // scale to repair against and is refused too; JUKF's singular P⁻ gets a jitter of 16ε × mean|Pᵢᵢ|
  // and the step is taken.
  const Snapshot<Filter> defaults(filter);
  const Status status = filter.timeUpdate(0.0, 0.01);
  if constexpr (IsJoint<Filter>::value) {
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

// A refused present component of a masked update, and an update with every component missing, which
// is taken and changes no estimate: the gain has only zero columns (MJUKF's θᵢ all become θ̂: its
// masked T has no weight left, so eq. 9 moves every θᵢ to θ̂, as documented).
TYPED_TEST(FailurePolicy, MaskedUpdates) {
  auto filter = TypeParam::template With<>::make(ToyModel());
  ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  using Mask = mjukf::MeasurementMask<1>;
  for (const double bad : {kNan, kInf, -kInf})
    expectRefusedAndUnchanged(filter, Status::NonFiniteMeasurement,
                              [&](auto& f) { return f.measurementUpdate(ToyModel::Meas(bad), Mask(true)); });
  ASSERT_EQ(filter.timeUpdate(0.01, 0.01), Status::Ok);
  const Snapshot<decltype(filter)> before(filter);
  ASSERT_EQ(filter.measurementUpdate(ToyModel::Meas(kNan), Mask(false)), Status::Ok);
  const Snapshot<decltype(filter)> after(filter);
  using mjukf::testing::bitwiseSame;
  EXPECT_TRUE(bitwiseSame(after.state, before.state));
  EXPECT_TRUE(bitwiseSame(after.covariance, before.covariance));
  EXPECT_TRUE(bitwiseSame(after.parameters, before.parameters));
  EXPECT_TRUE(bitwiseSame(after.parameterCovariance, before.parameterCovariance));
  EXPECT_FALSE(after.hasPropagatedPoints);  // an update was committed
  if constexpr (IsModifiedJoint<decltype(filter)>::value) {
    for (int i = 0; i < filter.parameterPoints().cols(); ++i)
      EXPECT_EQ(filter.parameterPoints()(0, i), filter.parameters()(0));
  }
}

// An outlier refused by the gate leaves everything as it was, the dual filter's parameter filter
// included (it is corrected before the state's gate decides, and must not be committed alone).
TYPED_TEST(FailurePolicy, GateRejectionLeavesTheFilterUnchanged) {
  const auto plain = TypeParam::template With<>::make(ToyModel());
  using Filter = std::decay_t<decltype(plain)>;
  auto settings = plain.settings();
  settings.gate = mjukf::MeasurementGate<double, 1>::chiSquare(0.999);  // NIS ≤ 10.83
  Filter filter(plain.model(), plain.state(), plain.parameters(), settings);
  ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  expectRefusedAndUnchanged(filter, Status::MeasurementRejected,
                            [](auto& f) { return f.measurementUpdate(ToyModel::Meas(1e3)); });
  EXPECT_GT(filter.lastUpdate().nis, 0.0);  // the follow-up update was taken
  ASSERT_EQ(filter.timeUpdate(0.01, 0.01), Status::Ok);
  expectRefusedAndUnchanged(filter, Status::MeasurementRejected, [](auto& f) {
    return f.measurementUpdate(ToyModel::Meas(-1e3), mjukf::MeasurementMask<1>(true));
  });
}

// The model fails at the sigma points only (|x| > 1.2 with x̂ ≈ 0.5 and P ≈ 1): the open-loop mean goes
// through; the time update is refused after the dual filter's parameter prediction (which propagates
// x̂ alone) has succeeded, so its candidates, and the prior the UpdatedParameters ordering keeps for its
// second time update, must not be committed: the follow-up measurement update shows they were not.
TYPED_TEST(FailurePolicy, ModelFailsAtTheSigmaPointsOnly) {
  ToyModel::BlowUp blowUp = ToyModel::BlowUp::Never;
  ToyModel model;
  model.blowUp = &blowUp;
  auto filter = TypeParam::template With<>::make(model);
  ASSERT_EQ(filter.timeUpdate(0.0, 0.01), Status::Ok);
  expectRefusedAndUnchanged(filter, Status::NonFiniteResult, [&blowUp](auto& f) {
    blowUp = ToyModel::BlowUp::LargeState;
    const Status s = f.timeUpdate(0.05, 0.02, 2);
    blowUp = ToyModel::BlowUp::Never;
    return s;
  });
  blowUp = ToyModel::BlowUp::LargeState;
  EXPECT_EQ(filter.propagateMean(0.01, 0.01), Status::Ok);
  blowUp = ToyModel::BlowUp::Never;
}

// ---------------------------------------------------------------------------------------------------
// The dual filter alone.

using DualUpdated = Toy<mjukf::DualUkf, mjukf::ITrBdf2<double>, mjukf::DualUkfOrdering::UpdatedParameters>;

// The UpdatedParameters ordering propagates again in its measurement update: a model failing there
// refuses the update, after the parameter filter's correction, and nothing of either is committed.
TEST(DualUkfFailurePolicy, ModelFailsInTheSecondTimeUpdate) {
  ToyModel::BlowUp blowUp = ToyModel::BlowUp::Never;
  ToyModel model;
  model.blowUp = &blowUp;
  auto filter = DualUpdated::make(model);
  // LargeState first, while P ≈ 1 lets the sigma points reach |x| > 1.2 (an update shrinks it).
  for (const auto mode : {ToyModel::BlowUp::LargeState, ToyModel::BlowUp::Derivative}) {
    ASSERT_EQ(filter.timeUpdate(0.01, 0.01), Status::Ok);
    expectRefusedAndUnchanged(filter, Status::NonFiniteResult, [&blowUp, mode](auto& f) {
      blowUp = mode;
      const Status s = f.measurementUpdate(ToyModel::Meas(0.3));
      blowUp = ToyModel::BlowUp::Never;
      return s;
    });
  }
}

// The tank observed in its upper level alone.
struct UpperLevelTank : mjukf::models::CoupledTank<double> {
  static constexpr int MeasDim = 1;
  using Meas = Eigen::Matrix<double, 1, 1>;
  Meas measurement(const State& x, const Param&) const { return Meas(x(0)); }
};

// A masked update is that of the model reduced to the components present, for both of the dual
// filter's filters: R and parameterObservationNoise reduced likewise. The masked update zeroes rows
// and columns and solves a 2 × 2 system where the reduced one solves 1 × 1, so the two differ by
// rounding alone, a few ε per step in a stable filter: over 2000 steps of the tank the relative
// difference stays below 1e-10 (the bound of the other filters' masking tests in robustness_test).
TEST(DualUkfFailurePolicy, MaskedUpdateEqualsTheReducedModel) {
  using Full = mjukf::models::CoupledTank<double>;
  for (const auto ordering : {mjukf::DualUkfOrdering::PriorParameters, mjukf::DualUkfOrdering::UpdatedParameters}) {
    mjukf::DualUkfSettingsFor<Full> sf;
    mjukf::DualUkfSettingsFor<UpperLevelTank> sr;
    sf.initialCovariance = sr.initialCovariance = 0.5 * Eigen::Matrix2d::Identity();
    sf.processNoise = sr.processNoise = 1e-5 * Eigen::Matrix2d::Identity();
    sf.measurementNoise << 0.09, 0.01, 0.01, 0.08;
    sr.measurementNoise << 0.09;
    sf.parameterObservationNoise << 0.05, 0.02, 0.02, 0.04;
    sr.parameterObservationNoise << 0.05;
    sf.initialParameterCovariance << 0.1;
    sr.initialParameterCovariance << 0.1;
    sf.parameterProcessNoise << 1e-5;
    sr.parameterProcessNoise << 1e-5;
    sf.ordering = sr.ordering = ordering;
    mjukf::DualUkf<Full> full(Full(), Full::State::Zero(), Full::Param::Constant(2.0), sf);
    mjukf::DualUkf<UpperLevelTank> reduced(UpperLevelTank(), Full::State::Zero(), Full::Param::Constant(2.0), sr);
    mjukf::testing::TankMeasurements<Full> data(1e-3, 0.3, 17);
    const mjukf::MeasurementMask<2> present(true, false);
    for (long k = 0; k < 2000; ++k) {
      const double t = double(k) * 1e-3;
      ASSERT_EQ(full.timeUpdate(t, 1e-3), Status::Ok);
      ASSERT_EQ(reduced.timeUpdate(t, 1e-3), Status::Ok);
      auto y = data.at(k + 1);
      y(1) = kNan;
      ASSERT_EQ(full.measurementUpdate(y, present), Status::Ok);
      ASSERT_EQ(reduced.measurementUpdate(UpperLevelTank::Meas(y(0))), Status::Ok);
    }
    EXPECT_TRUE(full.state().isApprox(reduced.state(), 1e-10));
    EXPECT_TRUE(full.covariance().isApprox(reduced.covariance(), 1e-10));
    EXPECT_TRUE(full.parameters().isApprox(reduced.parameters(), 1e-10));
    EXPECT_TRUE(full.parameterCovariance().isApprox(reduced.parameterCovariance(), 1e-10));
    EXPECT_NEAR(full.lastParameterUpdate().innovation(0), reduced.lastParameterUpdate().innovation(0), 1e-10);
    EXPECT_NEAR(full.lastParameterUpdate().nis, reduced.lastParameterUpdate().nis,
                1e-10 * reduced.lastParameterUpdate().nis);
    EXPECT_EQ(full.lastParameterUpdate().innovation(1), 0.0);  // the missing component, NaN in y
    EXPECT_GT(std::abs(full.parameters()(0) - 2.0), 1e-3);     // the parameter did move
  }
}

// Parameter bounds clamp θ̂ after every correction and leave P^θ alone: the robot's first guess is
// (K_τ, m) = (0.1, 0.15), the truth (0.15, 0.21); a box [0.09, 0.12] × [0.14, 0.18] holds the estimate
// below the truth, and it reaches the upper bounds (noiseless measurements of the truth, every step).
TEST(DualUkfFailurePolicy, ParameterBoundsClampTheEstimate) {
  using Robot = mjukf::paper::FlexibleJointExperiment<double>;
  const Robot::Model model;
  const Robot::Param truth = Robot::Model::trueParameters();
  for (const auto ordering : {mjukf::DualUkfOrdering::PriorParameters, mjukf::DualUkfOrdering::UpdatedParameters}) {
    auto s = Robot::dualUkf();
    s.ordering = ordering;
    s.parameterBounds.lower << 0.09, 0.14;
    s.parameterBounds.upper << 0.12, 0.18;
    mjukf::DualUkf<Robot::Model> filter(model, Robot::initialState(), Robot::initialParameters(), s);
    Robot::State x = Robot::State::Zero();
    const mjukf::ITrBdf2<double> stepper;
    bool reached[2] = {false, false};
    for (int k = 0; k < 4000; ++k) {
      x = stepper.step([&](double t, const Robot::State& z) { return model.derivative(t, z, model.input(t), truth); },
                       k * 1e-3, x, 1e-3);
      ASSERT_TRUE(mjukf::taken(filter.timeUpdate(k * 1e-3, 1e-3)));
      ASSERT_TRUE(mjukf::taken(filter.measurementUpdate(model.measurement(x, truth))));
      for (int i = 0; i < 2; ++i) {
        ASSERT_LE(filter.parameters()(i), s.parameterBounds.upper(i));
        ASSERT_GE(filter.parameters()(i), s.parameterBounds.lower(i));
        reached[i] = reached[i] || filter.parameters()(i) == s.parameterBounds.upper(i);
      }
      ASSERT_TRUE(mjukf::testing::symmetricPositiveDefinite(filter.parameterCovariance()));
    }
    EXPECT_TRUE(reached[0]);
    EXPECT_TRUE(reached[1]);
  }
}

// The dual filter in float: every refusal leaves it bit for bit unchanged, as in double.
TEST(DualUkfFailurePolicy, FloatRefusalsLeaveItUnchanged) {
  using Model = BasicToyModel<float>;
  constexpr float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (const auto ordering : {mjukf::DualUkfOrdering::PriorParameters, mjukf::DualUkfOrdering::UpdatedParameters}) {
    Model::BlowUp blowUp = Model::BlowUp::Never;
    Model model;
    model.blowUp = &blowUp;
    using Prior = Toy<mjukf::DualUkf, mjukf::ITrBdf2<float>, mjukf::DualUkfOrdering::PriorParameters, Model>;
    using Updated = Toy<mjukf::DualUkf, mjukf::ITrBdf2<float>, mjukf::DualUkfOrdering::UpdatedParameters, Model>;
    auto filter = ordering == mjukf::DualUkfOrdering::PriorParameters ? Prior::make(model) : Updated::make(model);
    ASSERT_EQ(filter.settings().ordering, ordering);
    ASSERT_EQ(filter.timeUpdate(0.0f, 0.01f), Status::Ok);
    // First, while P ≈ 1 lets the sigma points reach |x| > 1.2 (the updates below shrink it).
    expectRefusedAndUnchanged(filter, Status::NonFiniteResult, [&blowUp](auto& f) {
      blowUp = Model::BlowUp::LargeState;
      const Status s = f.timeUpdate(0.01f, 0.01f);
      blowUp = Model::BlowUp::Never;
      return s;
    });
    ASSERT_EQ(filter.timeUpdate(0.0f, 0.01f), Status::Ok);
    for (const float bad : {nan, inf, -inf}) {
      expectRefusedAndUnchanged(filter, Status::NonFiniteMeasurement,
                                [&](auto& f) { return f.measurementUpdate(Model::Meas(bad)); });
      ASSERT_EQ(filter.timeUpdate(0.0f, 0.01f), Status::Ok);
      expectRefusedAndUnchanged(filter, Status::NonFiniteInput,
                                [&](auto& f) { return f.timeUpdate(0.0f, 0.01f, Model::Input(bad)); });
      expectRefusedAndUnchanged(filter, Status::InvalidStepSize, [&](auto& f) { return f.timeUpdate(0.0f, bad); });
      ASSERT_EQ(filter.timeUpdate(0.0f, 0.01f), Status::Ok);
    }
    for (const auto mode : {Model::BlowUp::Derivative, Model::BlowUp::Measurement}) {
      expectRefusedAndUnchanged(filter, Status::NonFiniteResult, [&blowUp, mode](auto& f) {
        blowUp = mode;
        const Status s =
            mode == Model::BlowUp::Measurement ? f.measurementUpdate(Model::Meas(0.3f)) : f.timeUpdate(0.01f, 0.01f);
        blowUp = Model::BlowUp::Never;
        return s;
      });
      ASSERT_EQ(filter.timeUpdate(0.0f, 0.01f), Status::Ok);
    }
  }
}

}  // namespace
