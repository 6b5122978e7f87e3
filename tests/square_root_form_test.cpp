// The square-root covariance form (covariance_form.hpp, docs/algorithms.md §10) against the full form:
//  1. on the three reference files with the paper's presets and schedule, in double, every filter
//     (the dual in both orderings): the same statuses, and states, covariances and parameters equal to
//     a tolerance derived from rounding (below);
//  2. in float, the tank with near-exact measurements (R = 1e-7 ≪ P₀ = 0.5): the full form loses
//     definiteness and repairs or refuses, the square-root form holds and stays near double;
//  3. masked updates and the gate: the same as the full form, to the same tolerance;
//  4. the posterior branches (array form, downdate by U, fall-back) and negative weights.
// No allocation and the failure policy of the square-root filters are in the typed suites of
// no_allocation_test.cpp and failure_policy_test.cpp.
//
// The tolerance. Both forms compute the same quantities in exact arithmetic; they differ by rounding.
// In one measurement step each form computes weighted sums of Count terms, a triangularisation or a
// factorisation of L rows, and solves of M rows: its rounding error, relative to ‖P⁻‖, is at most
// about (Count + L + M) ε (the γ_n of Higham's bounds for sums, Householder QR and Cholesky, n the
// longest chain). Relative to ‖P⁺‖ that is (Count + L + M) ε r with r = ‖P⁻‖ / ‖P⁺‖, the cancellation of
// P⁺ = P⁻ − K P_yy Kᵀ (the full form's P⁺ is that much less accurate; r ≈ 100 on the tank, Q/R). The
// two forms' errors add: 2 (Count + L + M) ε r per step. A stable filter damps a difference in the
// state and a parameter estimate carries one along without amplifying it (a random walk, or eq. 10's
// mean), so over K measurement steps the differences accumulate at most linearly:
//
//     bound = 2 K (Count + L + M) ε r,   r = max over the run of ‖P⁻‖_F / ‖P⁺‖_F (measured, full form),
//
// applied to ‖x_sr − x‖ / ‖x‖, ‖P_sr − P‖_F / ‖P‖_F and ‖θ_sr − θ‖ / ‖θ‖ at every row (the dual: to
// both of its filters, with its parameter filter's sizes, the larger bound). The measured differences
// are printed beside the bound.

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "mjukf/covariance_form.hpp"
#include "mjukf/dual_ukf.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"
#include "paper/experiments.hpp"
#include "reference_data.hpp"
#include "robustness_support.hpp"
#include "test_support.hpp"

namespace {

using mjukf::Status;
using mjukf::testing::IsDual;
using mjukf::testing::referenceMeasurements;
using mjukf::testing::SquareRoot;

using Robot = mjukf::paper::FlexibleJointExperiment<double>;
using Tank = mjukf::paper::CoupledTankExperiment<double>;

template <class A, class B>
double relative(const A& sr, const B& full) {
  const double scale = full.template cast<double>().norm();
  const double difference = (sr.template cast<double>() - full.template cast<double>()).norm();
  return scale > 0 ? difference / scale : difference;
}

// The largest relative differences of a run, and the bound accumulated along it.
struct Comparison {
  double state = 0, covariance = 0, parameters = 0, parameterCovariance = 0;
  double bound = 0;                // Σ over the steps of what each step may add (the top of the file)
  double largestCancellation = 1;  // max r_k
  long updates = 0, openLoop = 0;
  long statusMismatches = 0;
  long masked = 0, rejected = 0;
  double largest() const { return std::max(std::max(state, covariance), std::max(parameters, parameterCovariance)); }
};

// What a run does on top of the paper's schedule.
struct Variant {
  int maskEvery = 0;     // every maskEvery-th update: component 0 missing (and NaN in y)
  bool redraw = false;   // redrawPointsForUpdate
  double gateNoise = 0;  // > 0: R = gateNoise I and the χ²(0.99) gate
  bool bounds = false;   // parameter bounds [θ̂₀ / 2, 3 θ̂₀ / 2] (JUKF, MJUKF, dual)
  std::string name() const {
    std::string n;
    if (maskEvery) n += " masked";
    if (redraw) n += " redraw";
    if (gateNoise > 0) n += " gated";
    if (bounds) n += " bounded";
    return n;
  }
  template <class Settings>
  void apply(Settings& s) const {
    using Scalar = typename Settings::Scalar;
    s.redrawPointsForUpdate = redraw;
    if (gateNoise > 0) {
      s.measurementNoise.setIdentity();
      s.measurementNoise *= Scalar(gateNoise);
      s.gate = decltype(s.gate)::chiSquare(Scalar(0.99));
    }
  }
  template <class Settings, class Param>
  void applyBounds(Settings& s, const Param& theta0) const {
    if (!bounds) return;
    s.parameterBounds.lower = theta0 / 2;
    s.parameterBounds.upper = theta0 * 3 / 2;
  }
};

template <class Full, class Sr>
void record(Comparison& c, const Full& full, const Sr& sr) {
  c.state = std::max(c.state, relative(sr.state(), full.state()));
  c.covariance = std::max(c.covariance, relative(sr.covariance(), full.covariance()));
  c.parameters = std::max(c.parameters, relative(sr.parameters(), full.parameters()));
  if constexpr (IsDual<Full>::value)
    c.parameterCovariance =
        std::max(c.parameterCovariance, relative(sr.parameterCovariance(), full.parameterCovariance()));
}

// The cancellation of P⁺ = P⁻ − K P_yy Kᵀ: the largest loss of a variance, max_i P⁻_ii / P⁺_ii.
template <class Matrix>
double cancellation(const Matrix& prior, const Matrix& posterior) {
  return (prior.diagonal().array() / posterior.diagonal().array()).template cast<double>().maxCoeff();
}

// Count + L + M of a filter's estimate (the dual: the larger of its two filters').
template <class Filter>
constexpr int chain() {
  const int state = Filter::SigmaPointCount + (Filter::SigmaPointCount - 1) / 2 + Filter::MeasDim;
  if constexpr (IsDual<Filter>::value)
    return std::max(state, Filter::ParameterSigmaPointCount + Filter::ParamDim + Filter::MeasDim);
  else
    return state;
}

// Both forms driven through the paper's schedule (paper::runSchedule's: a time update and a measurement
// update every `every` rows, the mean alone between them) over `y`, compared after every row, with the
// bound of each step added up: 2 (Count + L + M) ε r_k for a measurement step (r_k of the full form,
// of either of the dual's filters), plus 2 √ε with MJUKF's automatic modes; 2 (Count + L + M) ε for an
// open-loop step.
template <class Full, class Sr, class Meas>
Comparison compare(Full full, Sr sr, const std::vector<Meas>& y, typename Full::Scalar h, int every,
                   Variant variant = {}) {
  using Scalar = typename Full::Scalar;
  constexpr double epsilon = std::numeric_limits<Scalar>::epsilon();
  constexpr double step = 2.0 * chain<Full>() * epsilon;
  double automatic = 0;
  if constexpr (mjukf::testing::IsModifiedJoint<Full>::value)
    if (full.settings().automaticTransformation || full.settings().adaptiveScaling)
      automatic = 2.0 * std::sqrt(epsilon);
  Comparison c;
  for (long k = 0; k + 1 < long(y.size()); ++k) {
    const Scalar t = Scalar(k) * h;
    if ((k + 1) % every == 0) {
      const Status a = full.timeUpdate(t, h), b = sr.timeUpdate(t, h);
      c.statusMismatches += a != b;
      const auto prior = full.covariance();
      Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> parameterPrior;
      if constexpr (IsDual<Full>::value) parameterPrior = full.parameterCovariance();
      Meas yk = y[std::size_t(k + 1)];
      Status u, v;
      if (variant.maskEvery > 0 && c.updates % variant.maskEvery == 0) {
        mjukf::MeasurementMask<Meas::RowsAtCompileTime> present;
        present.setConstant(true);
        present(0) = false;
        yk(0) = std::numeric_limits<Scalar>::quiet_NaN();
        u = full.measurementUpdate(yk, present);
        v = sr.measurementUpdate(yk, present);
        ++c.masked;
      } else {
        u = full.measurementUpdate(yk);
        v = sr.measurementUpdate(yk);
      }
      c.statusMismatches += u != v;
      c.rejected += u == Status::MeasurementRejected;
      double r = 1;
      if (u == Status::Ok) {
        r = std::max(r, cancellation(prior, full.covariance()));
        if constexpr (IsDual<Full>::value) {
          const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> posterior = full.parameterCovariance();
          r = std::max(r, cancellation(parameterPrior, posterior));
        }
      }
      c.largestCancellation = std::max(c.largestCancellation, r);
      c.bound += step * r + automatic;
      ++c.updates;
    } else {
      c.statusMismatches += full.propagateMean(t, h) != sr.propagateMean(t, h);
      c.bound += step;
      ++c.openLoop;
    }
    record(c, full, sr);
  }
  return c;
}

void expectWithinBound(const Comparison& c, const std::string& what) {
  std::printf("%-48s K = %6ld  max r = %8.3g  bound %.2e | state %.2e  P %.2e  theta %.2e  P_theta %.2e  (%.1e of it)",
              what.c_str(), c.updates, c.largestCancellation, c.bound, c.state, c.covariance, c.parameters,
              c.parameterCovariance, c.largest() / c.bound);
  if (c.masked > 0) std::printf("  %ld masked", c.masked);
  if (c.rejected > 0) std::printf("  %ld rejected", c.rejected);
  std::printf("\n");
  EXPECT_EQ(c.statusMismatches, 0) << what;
  EXPECT_LE(c.state, c.bound) << what;
  EXPECT_LE(c.covariance, c.bound) << what;
  EXPECT_LE(c.parameters, c.bound) << what;
  EXPECT_LE(c.parameterCovariance, c.bound) << what;
}

// Every filter of an experiment in both forms over one reference file.
template <class Experiment>
void compareAllFilters(const char* file, Variant variant = {}, bool parameterChange = false) {
  using Model = typename Experiment::Model;
  const auto y = referenceMeasurements<typename Model::Meas>(file);
  const Model model;
  const auto x0 = Experiment::initialState();
  const auto theta0 = Experiment::initialParameters();
  const auto h = Experiment::stepSize;
  const int every = Experiment::measurementEvery;
  const auto label = [&](const char* filter) { return std::string(file) + variant.name() + " " + filter; };
  long rejected = 0;
  {
    auto s = Experiment::ukf();
    variant.apply(s);
    using Full = mjukf::Ukf<Model>;
    const auto c =
        compare(Full(model, x0, Model::trueParameters(), s),
                SquareRoot<mjukf::Ukf>::Filter<Model>(model, x0, Model::trueParameters(), s), y, h, every, variant);
    expectWithinBound(c, label("ukf"));
    rejected += c.rejected;
  }
  {
    auto s = Experiment::jointUkf();
    variant.apply(s);
    variant.applyBounds(s, theta0);
    using Full = mjukf::JointUkf<Model>;
    const auto c = compare(Full(model, x0, theta0, s), SquareRoot<mjukf::JointUkf>::Filter<Model>(model, x0, theta0, s),
                           y, h, every, variant);
    expectWithinBound(c, label("jukf"));
    rejected += c.rejected;
  }
  {
    auto s = Experiment::modifiedJointUkf();
    variant.apply(s);
    variant.applyBounds(s, theta0);
    if constexpr (std::is_same_v<Experiment, Robot>)
      if (parameterChange) s.scaling = Experiment::parameterChangeScaling;
    using Full = mjukf::ModifiedJointUkf<Model>;
    using Sr = SquareRoot<mjukf::ModifiedJointUkf>::Filter<Model>;
    auto c = compare(Full(model, x0, theta0, s), Sr(model, x0, theta0, s), y, h, every, variant);
    expectWithinBound(c, label("mjukf"));
    rejected += c.rejected;
    s.automaticTransformation = s.adaptiveScaling = true;
    c = compare(Full(model, x0, theta0, s), Sr(model, x0, theta0, s), y, h, every, variant);
    expectWithinBound(c, label("mjukf automatic"));
    rejected += c.rejected;
  }
  for (const auto ordering : {mjukf::DualUkfOrdering::PriorParameters, mjukf::DualUkfOrdering::UpdatedParameters}) {
    auto s = Experiment::dualUkf();
    variant.apply(s);
    variant.applyBounds(s, theta0);
    s.ordering = ordering;
    using Full = mjukf::DualUkf<Model>;
    const auto c = compare(Full(model, x0, theta0, s), SquareRoot<mjukf::DualUkf>::Filter<Model>(model, x0, theta0, s),
                           y, h, every, variant);
    expectWithinBound(c, label(ordering == mjukf::DualUkfOrdering::PriorParameters ? "dual prior" : "dual updated"));
    rejected += c.rejected;
  }
  if (variant.gateNoise > 0) {
    EXPECT_GT(rejected, 0) << "the gate rejected nothing: it was not tested";
  }
}

TEST(SquareRootForm, EqualsTheFullFormOnTheRobotReference) { compareAllFilters<Robot>("flexible_joint_reference.csv"); }

TEST(SquareRootForm, EqualsTheFullFormOnTheRobotParameterChangeReference) {
  compareAllFilters<Robot>("flexible_joint_param_change_reference.csv", {}, true);
}

TEST(SquareRootForm, EqualsTheFullFormOnTheTankReference) { compareAllFilters<Tank>("coupled_tank_reference.csv"); }

// Masked updates (every third, component 0 missing and NaN), points drawn afresh for every update,
// parameter bounds that clamp (the robot's K_τ reaches its upper bound 0.15), and the χ²(0.99) gate with
// R = 0.05 I (about the noise of the data, so that the gate passes most updates and rejects some).
TEST(SquareRootForm, MaskedRedrawnBoundedAndGatedUpdatesEqualTheFullForm) {
  compareAllFilters<Robot>("flexible_joint_reference.csv", Variant{3, false, 0, false});
  compareAllFilters<Robot>("flexible_joint_reference.csv", Variant{0, true, 0, false});
  compareAllFilters<Robot>("flexible_joint_reference.csv", Variant{0, false, 0, true});
  compareAllFilters<Robot>("flexible_joint_reference.csv", Variant{0, false, 0.05, false});
  compareAllFilters<Tank>("coupled_tank_reference.csv", Variant{3, true, 0, true});
}

}  // namespace

// ---- Float, near-exact measurements -------------------------------------------------------------------

struct StatusCounts {
  long ok = 0, repaired = 0, refused = 0;
  long firstTrouble = -1;  // the row of the first step repaired or refused
  void add(Status s, long row) {
    ok += s == Status::Ok;
    repaired += s == Status::Repaired;
    refused += !mjukf::taken(s);
    if (s != Status::Ok && firstTrouble < 0) firstTrouble = row;
  }
};

// A run of the paper's schedule that goes on after every step, refused ones included: the statuses, the
// estimates after every row, and the conditioning of the committed P (κ₂ = λ_max / λ_min, and the
// largest P⁻_ii / R_ii before a measurement update).
struct FloatRun {
  StatusCounts counts;
  std::vector<Eigen::VectorXd> states, parameters, deviations;  // deviations: √P_ii of the state block
  double kappa = 0, priorOverNoise = 0;
};

template <class Filter, class Meas>
FloatRun runCounting(Filter f, const std::vector<Meas>& y, typename Filter::Scalar h, int every) {
  using Scalar = typename Filter::Scalar;
  FloatRun run;
  const auto noise = f.settings().measurementNoise.diagonal().template cast<double>().eval();
  for (long k = 0; k + 1 < long(y.size()); ++k) {
    const Scalar t = Scalar(k) * h;
    if ((k + 1) % every == 0) {
      run.counts.add(f.timeUpdate(t, h), k + 1);
      const Eigen::VectorXd prior = f.covariance().diagonal().template head<Filter::MeasDim>().template cast<double>();
      run.priorOverNoise = std::max(run.priorOverNoise, prior.cwiseQuotient(noise).maxCoeff());
      run.counts.add(f.measurementUpdate(y[std::size_t(k + 1)]), k + 1);
      const Eigen::MatrixXd p = f.covariance().template cast<double>();
      const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(p).eigenvalues();
      run.kappa = std::max(run.kappa, lambda.minCoeff() > 0 ? lambda.maxCoeff() / lambda.minCoeff()
                                                            : std::numeric_limits<double>::infinity());
    } else {
      run.counts.add(f.propagateMean(t, h), k + 1);
    }
    run.states.push_back(f.state().template cast<double>());
    run.parameters.push_back(f.parameters().template cast<double>());
    run.deviations.push_back(
        f.covariance().diagonal().template head<Filter::StateDim>().template cast<double>().cwiseSqrt());
  }
  return run;
}

// The largest |x_float − x_double|ᵢ / σᵢ over the run, σᵢ = √P_ii of the double reference: the float
// estimate's error in units of the uncertainty the filter itself reports.
double normalisedStateError(const FloatRun& single, const FloatRun& reference) {
  double worst = 0;
  for (std::size_t k = 0; k < reference.states.size(); ++k)
    worst = std::max(
        worst, (single.states[k] - reference.states[k]).cwiseAbs().cwiseQuotient(reference.deviations[k]).maxCoeff());
  return worst;
}

// The tank in float, with near-exact measurements: R = 1e-8 I against P₀ = 0.5 I (P₀/R = 5e7, beyond
// 1/ε_float = 8.4e6) and the textbook update (redrawPointsForUpdate: the points carry Q, so P⁺ falls to
// the level of R; the paper's Algorithm 1 keeps P⁺ ≥ Q = 1e-5 and the full form holds even at
// R = 1e-10). P⁺ = P⁻ − K P_yy Kᵀ is then all cancellation in float: the full form has to repair or
// refuse covariances that rounding left indefinite, and a refused update leaves the state uncorrected;
// the square-root form takes every step and stays near the double reference (the bound below).
// First 20 s of the reference file; the reference is the full form in double (it takes every step).
TEST(SquareRootForm, FloatTankWithNearExactMeasurements) {
  using TankF = mjukf::paper::CoupledTankExperiment<float>;
  using ModelF = TankF::Model;
  using ModelD = Tank::Model;
  auto yd = referenceMeasurements<ModelD::Meas>("coupled_tank_reference.csv");
  yd.resize(20001);
  std::vector<ModelF::Meas> yf(yd.size());
  for (std::size_t k = 0; k < yd.size(); ++k) yf[k] = yd[k].cast<float>();
  const auto nearExact = [](auto s) {
    s.measurementNoise.setIdentity();
    s.measurementNoise *= 1e-8f;
    s.redrawPointsForUpdate = true;
    return s;
  };
  const auto report = [](const char* what, const FloatRun& r) {
    std::printf("%-28s ok %6ld  repaired %3ld  refused %3ld  first at row %6ld  max kappa(P) %.3g  max P-/R %.3g\n",
                what, r.counts.ok, r.counts.repaired, r.counts.refused, r.counts.firstTrouble, r.kappa,
                r.priorOverNoise);
  };
  long fullTrouble = 0;
  const auto check = [&](const char* name, const FloatRun& reference, const FloatRun& full, const FloatRun& sr) {
    report((std::string(name) + " double, full").c_str(), reference);
    report((std::string(name) + " float, full").c_str(), full);
    report((std::string(name) + " float, square root").c_str(), sr);
    EXPECT_EQ(reference.counts.ok, long(2 * 10000 + 10000)) << name << ": the double reference takes every step";
    EXPECT_EQ(sr.counts.ok, reference.counts.ok) << name << ": the square-root form takes every step";
    fullTrouble += full.counts.repaired + full.counts.refused;
    double theta = 0;
    for (std::size_t k = 0; k < reference.parameters.size(); ++k)
      theta = std::max(theta, (sr.parameters[k] - reference.parameters[k]).norm() / reference.parameters[k].norm());
    const double srError = normalisedStateError(sr, reference), fullError = normalisedStateError(full, reference);
    std::printf("%-28s |x_float - x_double| / sigma: square root %.3g, full %.3g; theta (square root) %.2e relative\n",
                name, srError, fullError, theta);
    // 0.1 σ: what float rounding leaves in a filter with a well-conditioned P (measured 0.046 for the UKF
    // and MJUKF here); plus 2 κ(P) ε_float, the amplification of relative rounding by a solve of
    // condition κ(P) (the JUKF's P, with the parameters' variances, has κ = 1e7: 2.4 σ; its full form
    // in float, where it takes the step, is no less accurate: the square-root form's gain there is the
    // step it does not have to repair).
    const double bound = 0.1 + 2 * reference.kappa * std::numeric_limits<float>::epsilon();
    EXPECT_LE(srError, bound) << name;
  };
  {
    const auto s = nearExact(Tank::ukf());
    const auto sf = nearExact(TankF::ukf());
    const auto theta = ModelD::trueParameters();
    const auto thetaF = ModelF::trueParameters();
    check("ukf", runCounting(mjukf::Ukf<ModelD>(ModelD(), Tank::initialState(), theta, s), yd, Tank::stepSize, 2),
          runCounting(mjukf::Ukf<ModelF>(ModelF(), TankF::initialState(), thetaF, sf), yf, TankF::stepSize, 2),
          runCounting(SquareRoot<mjukf::Ukf>::Filter<ModelF>(ModelF(), TankF::initialState(), thetaF, sf), yf,
                      TankF::stepSize, 2));
  }
  {
    const auto s = nearExact(Tank::jointUkf());
    const auto sf = nearExact(TankF::jointUkf());
    check("jukf",
          runCounting(mjukf::JointUkf<ModelD>(ModelD(), Tank::initialState(), Tank::initialParameters(), s), yd,
                      Tank::stepSize, 2),
          runCounting(mjukf::JointUkf<ModelF>(ModelF(), TankF::initialState(), TankF::initialParameters(), sf), yf,
                      TankF::stepSize, 2),
          runCounting(SquareRoot<mjukf::JointUkf>::Filter<ModelF>(ModelF(), TankF::initialState(),
                                                                  TankF::initialParameters(), sf),
                      yf, TankF::stepSize, 2));
  }
  {
    const auto s = nearExact(Tank::modifiedJointUkf());
    const auto sf = nearExact(TankF::modifiedJointUkf());
    check("mjukf",
          runCounting(mjukf::ModifiedJointUkf<ModelD>(ModelD(), Tank::initialState(), Tank::initialParameters(), s), yd,
                      Tank::stepSize, 2),
          runCounting(mjukf::ModifiedJointUkf<ModelF>(ModelF(), TankF::initialState(), TankF::initialParameters(), sf),
                      yf, TankF::stepSize, 2),
          runCounting(SquareRoot<mjukf::ModifiedJointUkf>::Filter<ModelF>(ModelF(), TankF::initialState(),
                                                                          TankF::initialParameters(), sf),
                      yf, TankF::stepSize, 2));
  }
  EXPECT_GT(fullTrouble, 0) << "the full form in float repaired or refused nothing: the case does not show the point";
}

// ---- The posterior branches, on one estimate ------------------------------------------------------------

// One estimate of a 3-vector measured through 2 components in both forms, driven by hand: a nonlinear
// propagation of its points, then the correction of the propagated points with the prior as it is
// (Predicted: the square-root form's array form with G), of points drawn afresh (Drawn: the array form
// without G) and of the propagated points declared Other (the downdate of S⁻ by U).
template <class Form>
using Est = mjukf::detail::Estimate<double, 3, 2, mjukf::MerweScaled, Form>;

struct Branches {
  Eigen::Matrix3d q = 1e-4 * Eigen::Matrix3d::Identity();
  Eigen::Matrix2d r = (Eigen::Matrix2d() << 1e-2, 2e-3, 2e-3, 5e-3).finished();
  Eigen::Vector3d x0 = Eigen::Vector3d(0.3, -0.2, 0.5);
  Eigen::Matrix3d p0 = (Eigen::Matrix3d() << 0.5, 0.1, 0.0, 0.1, 0.4, -0.05, 0.0, -0.05, 0.3).finished();
  Eigen::Vector2d y = Eigen::Vector2d(0.1, 0.45);
  mjukf::MeasurementGate<double, 2> gate;
  mjukf::CovarianceRepair<double> repair;
  bool linear = false;  // measure x₀ + x₁ and x₂ instead (no nonlinearity adding to P_yy)

  static void propagate(Eigen::Matrix<double, 3, Est<mjukf::FullCovariance>::Count>& points) {
    for (int i = 0; i < points.cols(); ++i) {
      const Eigen::Vector3d x = points.col(i);
      points.col(i) << x(0) + 0.1 * std::sin(x(1)), x(1) + 0.1 * x(2), 0.9 * x(2) + 0.05 * x(0) * x(0);
    }
  }
  template <class E>
  typename E::MeasPoints measure(const typename E::Points& points) const {
    typename E::MeasPoints measured;
    for (int i = 0; i < points.cols(); ++i) {
      if (linear)
        measured.col(i) << points(0, i) + points(1, i), points(2, i);
      else
        measured.col(i) << points(0, i) * points(0, i) + points(1, i), std::sin(points(2, i));
    }
    return measured;
  }
  // One time update into `e`, committed.
  template <class E>
  void predict(E& e) const {
    ASSERT_EQ(e.draw(e.mean(), e.factor()), Status::Ok);
    propagate(e.workPoints());
    e.predict(q);
    ASSERT_EQ(e.settle(repair), Status::Ok);
    e.commitPrediction();
  }
  // The correction of `e`'s committed estimate from its propagated points (drawn = false) or from points
  // drawn now, with the prior declared `points`; the candidate covariance and mean, and the status.
  template <class E>
  Status correct(E& e, bool drawn, mjukf::detail::PriorPoints points, const mjukf::MeasurementMask<2>* present,
                 Eigen::Matrix3d& covariance, Eigen::Vector3d& mean) const {
    if (drawn) e.draw(e.mean(), e.factor());
    const typename E::Points chosen = drawn ? e.workPoints() : e.points();
    const typename E::Prior prior{e.mean(), e.covariance(), e.factor(), points};
    const Status s = e.correct(chosen, measure<E>(chosen), prior, y, r, present, gate);
    if (s != Status::Ok) return s;
    const Status settled = e.settle(repair);
    covariance = e.candidateCovariance();
    mean = e.candidateMean();
    return settled;
  }
};

TEST(SquareRootEstimate, EveryPosteriorBranchEqualsTheFullForm) {
  using mjukf::detail::PriorPoints;
  using mjukf::detail::Validated;
  for (const double alpha : {1.0, 0.5}) {  // α = 0.5: Wc₀ = −0.25, a downdate in every factorisation
    Branches b;
    mjukf::SigmaPointParameters<double> sigma;
    sigma.alpha = alpha;
    Est<mjukf::FullCovariance> full(Validated{}, sigma, b.q, b.r);
    Est<mjukf::SquareRootCovariance> sr(Validated{}, sigma, b.q, b.r);
    ASSERT_EQ(sr.sigmaPoints().covarianceWeights()(0) < 0, alpha < 1);
    ASSERT_TRUE(full.assign(b.x0, b.p0));
    ASSERT_TRUE(sr.assign(b.x0, b.p0));
    b.predict(full);
    b.predict(sr);
    ASSERT_EQ(sr.prior(false).points, PriorPoints::Predicted);
    // P⁻ of the two forms: one time update, 2 (Count + L) ε relative.
    EXPECT_LE(relative(sr.covariance(), full.covariance()), 2 * (7 + 3) * 2.3e-16);
    mjukf::MeasurementMask<2> secondOnly(false, true);
    for (const mjukf::MeasurementMask<2>* present : {static_cast<const mjukf::MeasurementMask<2>*>(nullptr),
                                                     static_cast<const mjukf::MeasurementMask<2>*>(&secondOnly)}) {
      for (const bool drawn : {false, true}) {
        Eigen::Matrix3d pf = Eigen::Matrix3d::Zero(), ps = pf, po = pf;
        Eigen::Vector3d mf = Eigen::Vector3d::Zero(), ms = mf, mo = mf;
        Est<mjukf::FullCovariance> f = full;
        Est<mjukf::SquareRootCovariance> s = sr, o = sr;
        ASSERT_EQ(b.correct(f, drawn, PriorPoints::Other, present, pf, mf), Status::Ok);
        ASSERT_EQ(b.correct(s, drawn, drawn ? PriorPoints::Drawn : PriorPoints::Predicted, present, ps, ms),
                  Status::Ok);
        ASSERT_EQ(b.correct(o, drawn, PriorPoints::Other, present, po, mo), Status::Ok);
        // One measurement step: 2 (Count + L + M) ε r, r = max P⁻_ii / P⁺_ii.
        const double r = (full.covariance().diagonal().array() / pf.diagonal().array()).maxCoeff();
        const double bound = 2 * (7 + 3 + 2) * 2.3e-16 * r;
        const std::string what = std::string(drawn ? "drawn" : "propagated") + (present ? ", masked" : "") +
                                 ", alpha " + std::to_string(alpha);
        EXPECT_LE(relative(ps, pf), bound) << what << " (array form)";
        EXPECT_LE(relative(po, pf), bound) << what << " (downdate by U)";
        EXPECT_LE(relative(ms, mf), bound) << what;
        EXPECT_LE(relative(mo, mf), bound) << what;
        EXPECT_TRUE((ps.array() == ps.transpose().array()).all()) << what;
      }
    }
  }
}

// A near-exact linear measurement in double, R = 1e-20 I against P⁻ of order 0.5, with points drawn
// afresh (so that they carry all of P⁻ and the update can take P⁺ down to the level of R in the two
// measured directions c = x₀ + x₁ and x₂). The full form's P⁺ = P⁻ − K P_yy Kᵀ is there all cancellation:
// its rounding, of order ε ‖P⁻‖ = 1e-16, is 10⁴ R, and leaves P⁺ indefinite, which the repair mends
// (Repaired) at a variance of the measured directions of 10⁴ R or more. The square-root form's array
// form forms no difference: the factor's rows C S⁺ are computed to an absolute error of a few ε ‖S⁻‖
// (Householder's backward error in each row of the stack), so the measured directions' variance is R up
// to that. The downdate of S⁻ by U cannot hold the margin 1 − ‖S⁻¹u‖² > 4N ε (its exact value is about
// R / P), so that branch falls back to the full form's P and gives the full form's status.
TEST(SquareRootEstimate, NearExactMeasurementTheArrayFormHolds) {
  using mjukf::detail::PriorPoints;
  using mjukf::detail::Validated;
  Branches b;
  b.linear = true;
  const double r = 1e-20;
  b.r = r * Eigen::Matrix2d::Identity();
  Est<mjukf::FullCovariance> full(Validated{}, {}, b.q, b.r);
  Est<mjukf::SquareRootCovariance> sr(Validated{}, {}, b.q, b.r);
  ASSERT_TRUE(full.assign(b.x0, b.p0));
  ASSERT_TRUE(sr.assign(b.x0, b.p0));
  b.predict(full);
  b.predict(sr);
  const double priorFactorNorm = sr.factor().norm();
  Eigen::Matrix3d pf = Eigen::Matrix3d::Zero(), ps = pf, po = pf;
  Eigen::Vector3d mf = Eigen::Vector3d::Zero(), ms = mf, mo = mf;
  Est<mjukf::SquareRootCovariance> other = sr;
  const Status f = b.correct(full, true, PriorPoints::Other, nullptr, pf, mf);
  const Status s = b.correct(sr, true, PriorPoints::Drawn, nullptr, ps, ms);
  const Status o = b.correct(other, true, PriorPoints::Other, nullptr, po, mo);
  EXPECT_EQ(f, Status::Repaired);
  EXPECT_EQ(s, Status::Ok);
  EXPECT_EQ(o, f);
  const Eigen::Matrix<double, 2, 3> c = (Eigen::Matrix<double, 2, 3>() << 1, 1, 0, 0, 0, 1).finished();
  // Square root: each row of C S⁺ has norm at most √R (exactly: the variance R − R P_yy⁻¹ R < R) plus
  // the rounding of the stack's triangularisation, 2 (Count + L + M) ε ‖S⁻‖ per row, times ‖c‖ ≤ √2.
  const Eigen::Matrix<double, 2, 3> measuredFactor = c * sr.candidateFactor();
  const double rowBound = std::sqrt(r) + std::sqrt(2.0) * 2 * (7 + 3 + 2) * 2.3e-16 * priorFactorNorm;
  for (int j = 0; j < 2; ++j) EXPECT_LE(measuredFactor.row(j).norm(), rowBound) << "measured direction " << j;
  // Full: the repaired P⁺ keeps rounding of order ε ‖P⁻‖ ≫ R in the measured directions.
  const Eigen::Matrix2d measuredFull = c * pf * c.transpose();
  EXPECT_GT(measuredFull.diagonal().maxCoeff(), 100 * r);
  // Both keep the unmeasured direction's variance.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(ps);
  EXPECT_GT(eigen.eigenvalues().maxCoeff(), 1e-3);
}
