#pragma once

/// \file
/// Offline, on the host: an estimate of the initial state x₀ from the first samples of a record, for
/// states that are not measured (docs/offline-passes.md). Levenberg–Marquardt on the free run's output
/// error over those samples. Fixed sizes, no allocation. Not included by mjukf/mjukf.hpp.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "mjukf/detail/linear_algebra.hpp"
#include "mjukf/offline/free_run.hpp"

namespace mjukf::offline {

/// The settings of `estimateInitialState` for a model of `StateDim` states and `MeasDim` outputs.
template <class Scalar, int StateDim, int MeasDim>
struct InitialStateSettings {
  /// Components held at the guess, not estimated: those measured directly, set from y₀ first (over a
  /// few samples the output says little more about them than y₀ does, and fixing them leaves the
  /// samples to the others).
  Eigen::Matrix<bool, StateDim, 1> fixed = Eigen::Matrix<bool, StateDim, 1>::Constant(false);
  /// The standard deviation of each output's noise: the residuals are weighed by its inverse, and the
  /// estimate's `covariance` is in the state's units when it is the noise's. Must be > 0.
  Eigen::Matrix<Scalar, MeasDim, 1> noiseStd = Eigen::Matrix<Scalar, MeasDim, 1>::Ones();
  /// The typical size of each state: the finite-difference step is √ε max(|xᵢ|, scaleᵢ), and the
  /// stopping test adds it to |xᵢ|. Must be > 0.
  Eigen::Matrix<Scalar, StateDim, 1> typicalScale = Eigen::Matrix<Scalar, StateDim, 1>::Ones();
  /// Stop when an accepted step moves every free xᵢ by at most this times |xᵢ| + scaleᵢ.
  Scalar stepTolerance = Scalar(1e-10);
  /// The most Levenberg–Marquardt iterations (each one free run, and n more when a step is accepted).
  int maxIterations = 100;
  /// λ of the first step, relative to the diagonal of JᵀJ (Marquardt's scaling).
  Scalar initialDamping = Scalar(1e-3);
};

/// What `estimateInitialState` found.
template <class Scalar, int StateDim>
struct InitialStateEstimate {
  /// x̂₀ (the fixed components as given).
  Eigen::Matrix<Scalar, StateDim, 1> state;
  /// (JᵀWJ)⁻¹ on the free components at x̂₀, W = diag(1 / noiseStd²), zero on the fixed ones: the
  /// linearised covariance of x̂₀ when the noise is white with that standard deviation. +∞ on the
  /// diagonal of the free components when JᵀWJ is singular (not observable over these samples).
  Eigen::Matrix<Scalar, StateDim, StateDim> covariance;
  /// ½ Σ_k ‖W^½ (y_k − ŷ_k)‖² at the guess.
  Scalar initialCost = 0;
  /// ½ Σ_k ‖W^½ (y_k − ŷ_k)‖² at x̂₀.
  Scalar cost = 0;
  /// The condition number of JᵀWJ on the free components scaled by `typicalScale`: large (against
  /// 1 / ε) when the samples hardly tell some combination of the free states apart.
  Scalar conditionNumber = 0;
  /// Iterations taken.
  int iterations = 0;
  /// true when the stopping test held (or no step could lower the cost any more, and the last was below
  /// the tolerance); false after `maxIterations`, or when the free run at the guess is not finite.
  bool converged = false;
  /// true when JᵀWJ on the free components was positive definite at x̂₀.
  bool observable = false;
};

/// \cond INTERNAL
namespace detail {

// The free run from x₀ and from x₀ + δᵢ eᵢ for each free i, sample by sample together, into the
// weighted normal equations A = Σ JₖᵀWJₖ, b = Σ JₖᵀW rₖ and the cost ½ Σ rₖᵀW rₖ, with
// rₖ = yₖ − ŷₖ(x₀) and Jₖ's column i = (ŷₖ(x₀ + δᵢ eᵢ) − ŷₖ(x₀)) / δᵢ. Components of yₖ that are NaN
// are skipped. With `jacobian` false, the cost alone (one free run).
template <class Model, class Integrator, class InputRecord, class Measured, class Settings>
struct InitialStateProblem {
  using Scalar = typename Model::Scalar;
  static constexpr int N = Model::StateDim, M = Model::MeasDim;
  using State = typename Model::State;
  using Matrix = Eigen::Matrix<Scalar, N, N>;

  const Model& model;
  const Integrator& integrator;
  const typename Model::Param& theta;
  const InputRecord& inputs;
  const Measured& measured;
  const Sampling<Scalar>& sampling;
  std::size_t samples;
  const Settings& settings;

  Scalar evaluate(const State& x0, bool jacobian, Matrix& a, State& b) const {
    Eigen::Matrix<Scalar, N, N> starts;  // column i: x₀ + δᵢ eᵢ
    State delta = State::Zero();
    for (int i = 0; i < N; ++i) {
      starts.col(i) = x0;
      if (!jacobian || settings.fixed(i)) continue;
      const Scalar step =
          std::sqrt(std::numeric_limits<Scalar>::epsilon()) * std::max(std::abs(x0(i)), settings.typicalScale(i));
      starts(i, i) = x0(i) + step;
      delta(i) = starts(i, i) - x0(i);  // the step as represented
    }
    a.setZero();
    b.setZero();
    Scalar cost = 0;
    const Scalar h = sampling.period / Scalar(sampling.subSteps);
    State x = x0;
    for (std::size_t k = 0; k < samples; ++k) {
      const Scalar t = sampling.startTime + Scalar(k) * sampling.period;
      const auto u = inputs.measurementInput(k, t);
      const typename Model::Meas nominal = measureModel(model, x, u, theta);
      Eigen::Matrix<Scalar, M, N> j = Eigen::Matrix<Scalar, M, N>::Zero();
      if (jacobian)
        for (int i = 0; i < N; ++i)
          if (!settings.fixed(i)) j.col(i) = (measureModel(model, State(starts.col(i)), u, theta) - nominal) / delta(i);
      typename Model::Meas r;
      for (int c = 0; c < M; ++c) {
        const bool present = !std::isnan(measured[k](c));
        r(c) = present ? (measured[k](c) - nominal(c)) / settings.noiseStd(c) : Scalar(0);
        if (present)
          j.row(c) /= settings.noiseStd(c);
        else
          j.row(c).setZero();
      }
      cost += r.squaredNorm() / Scalar(2);
      if (jacobian) {
        a.noalias() += j.transpose() * j;
        b.noalias() += j.transpose() * r;
      }
      if (k + 1 == samples) break;
      x = inputs.advance(model, integrator, x, theta, k, t, h, sampling.subSteps);
      if (jacobian)
        for (int i = 0; i < N; ++i)
          if (!settings.fixed(i))
            starts.col(i) = inputs.advance(model, integrator, State(starts.col(i)), theta, k, t, h, sampling.subSteps);
    }
    return std::isfinite(cost) && mjukf::detail::allFinite(a) && mjukf::detail::allFinite(b)
               ? cost
               : std::numeric_limits<Scalar>::infinity();
  }
};

template <class Problem, class Settings>
auto estimateInitialStateWith(const Problem& problem, const typename Problem::State& guess, const Settings& s) {
  using Scalar = typename Problem::Scalar;
  constexpr int N = Problem::N;
  using State = typename Problem::State;
  using Matrix = typename Problem::Matrix;
  InitialStateEstimate<Scalar, N> result;
  result.state = guess;
  result.covariance.setZero();
  const Scalar inf = std::numeric_limits<Scalar>::infinity();

  Matrix a, unused;
  State b, unusedB;
  Scalar cost = problem.evaluate(guess, true, a, b);
  result.initialCost = result.cost = cost;
  if (!std::isfinite(cost)) return result;
  State x = guess;
  Scalar lambda = s.initialDamping;
  for (result.iterations = 1; result.iterations <= s.maxIterations; ++result.iterations) {
    // (A + λ D) Δ = b on the free components (D = diag(A), floored so that a component the samples do
    // not see keeps a finite step); a fixed one gets a unit row and column and a zero right-hand side.
    Matrix damped = a;
    State rhs = b;
    const Scalar floor = std::numeric_limits<Scalar>::epsilon() * std::max(a.diagonal().maxCoeff(), Scalar(1));
    for (int i = 0; i < N; ++i) {
      if (s.fixed(i)) {
        damped.row(i).setZero();
        damped.col(i).setZero();
        damped(i, i) = Scalar(1);
        rhs(i) = Scalar(0);
      } else {
        damped(i, i) += lambda * std::max(a(i, i), floor);
      }
    }
    Matrix factor;
    State step = rhs;
    const bool solved = mjukf::detail::choleskyLower(damped, factor);
    if (solved) {
      mjukf::detail::solveLowerInPlace(factor, step);
      mjukf::detail::solveUpperInPlace(factor, step);
    }
    bool small = solved;
    for (int i = 0; i < N && small; ++i)
      small = std::abs(step(i)) <= s.stepTolerance * (std::abs(x(i)) + s.typicalScale(i));
    const State trial = x + step;
    const Scalar trialCost = solved ? problem.evaluate(trial, false, unused, unusedB) : inf;
    if (trialCost < cost) {
      x = trial;
      cost = problem.evaluate(x, true, a, b);
      // A small step under heavy damping says little; near Gauss–Newton (λ < 1) it is the answer.
      const bool done = small && lambda < Scalar(1);
      lambda = std::max(lambda / Scalar(10), Scalar(1e-12));
      if (done) {
        result.converged = true;
        break;
      }
    } else {
      // Not even a step below the tolerance lowers the cost: the minimum, to rounding.
      if (small) {
        result.converged = true;
        break;
      }
      lambda *= Scalar(10);
      if (lambda > Scalar(1e16)) break;
    }
  }
  result.iterations = std::min(result.iterations, s.maxIterations);
  result.state = x;
  result.cost = cost;

  // The covariance and the conditioning on the free components (fixed ones: unit row and column).
  Matrix freeBlock = a;
  int freeCount = 0;
  for (int i = 0; i < N; ++i) {
    if (s.fixed(i)) {
      freeBlock.row(i).setZero();
      freeBlock.col(i).setZero();
      freeBlock(i, i) = Scalar(1);
    } else {
      ++freeCount;
    }
  }
  Matrix factor;
  result.observable = freeCount > 0 && mjukf::detail::choleskyLower(freeBlock, factor);
  if (result.observable) {
    Matrix inverse = Matrix::Identity();
    mjukf::detail::solveLowerInPlace(factor, inverse);
    mjukf::detail::solveUpperInPlace(factor, inverse);
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) result.covariance(i, j) = s.fixed(i) || s.fixed(j) ? Scalar(0) : inverse(i, j);
  } else {
    for (int i = 0; i < N; ++i)
      if (!s.fixed(i)) result.covariance(i, i) = inf;
  }
  Matrix scaled = s.typicalScale.asDiagonal() * freeBlock * s.typicalScale.asDiagonal();
  for (int i = 0; i < N; ++i)
    if (s.fixed(i)) scaled(i, i) = scaled.diagonal().maxCoeff();  // neutral: does not set the condition
  const Eigen::SelfAdjointEigenSolver<Matrix> eigen(scaled, Eigen::EigenvaluesOnly);
  const Scalar smallest = eigen.eigenvalues().minCoeff(), largest = eigen.eigenvalues().maxCoeff();
  result.conditionNumber = smallest > Scalar(0) ? largest / smallest : inf;
  return result;
}

}  // namespace detail
/// \endcond

/// An estimate of x₀ from the first `samples` measured outputs of a record, for states that are not
/// measured. It minimises the weighted output error of the free run (`freeRun`, same sampling and
/// inputs) over samples 0 … samples − 1,
///
///     ½ Σ_k Σ_j ((y_kj − ŷ_kj(x₀)) / σ_j)²,   σ = settings.noiseStd,
///
/// over the components of x₀ not held fixed, by Levenberg–Marquardt from `guess`: forward-difference
/// Jacobians (one extra free run per free component), Marquardt's diagonal scaling, λ divided by 10
/// after a step that lowers the cost and multiplied by 10 otherwise. NaN measurements are skipped.
///
/// Limits: the samples must determine x₀, i.e. the map x₀ ↦ (ŷ_0 … ŷ_{N−1}) must be locally one-to-one
/// on the free components (observability over N samples). A state that reaches the outputs only
/// through slow dynamics moves them little over a few periods, so its estimate is as uncertain as the
/// noise divided by that movement: `covariance` says how much, `conditionNumber` how close to
/// unobservable. The model and θ are taken as exact (a wrong θ biases x̂₀), the minimum found is the
/// one nearest the guess, and the covariance is the linearisation's.
///
/// `inputs[k]` (Model::Input) are held over each period as in `freeRun`; `measured[k]` (Model::Meas)
/// are the record's outputs, at least `samples` of both. Bad sampling, too few samples in a record or
/// samples < 1 throw std::invalid_argument (without exceptions: the guess, not converged).
template <class Model, class Integrator, class Inputs, class Measured>
InitialStateEstimate<typename Model::Scalar, Model::StateDim> estimateInitialState(
    const Model& model, const Integrator& integrator, const typename Model::Param& theta, const Inputs& inputs,
    const Measured& measured, const Sampling<typename Model::Scalar>& sampling, std::size_t samples,
    const typename Model::State& guess,
    const InitialStateSettings<typename Model::Scalar, Model::StateDim, Model::MeasDim>& settings = {}) {
  using Scalar = typename Model::Scalar;
  using Settings = InitialStateSettings<Scalar, Model::StateDim, Model::MeasDim>;
  const bool valid =
      (detail::validSampling(sampling) || detail::refuse("estimateInitialState: the sampling is not valid")) &&
      ((samples >= 1 && inputs.size() >= samples && measured.size() >= samples) ||
       detail::refuse("estimateInitialState: samples must be >= 1 and within both records")) &&
      (((settings.noiseStd.array() > Scalar(0)).all() && (settings.typicalScale.array() > Scalar(0)).all()) ||
       detail::refuse("estimateInitialState: noiseStd and typicalScale must be > 0"));
  if (!valid) {
    InitialStateEstimate<Scalar, Model::StateDim> r;
    r.state = guess;
    r.covariance.setZero();
    return r;
  }
  using Record = detail::HeldSamples<Model, Inputs>;
  const Record record{inputs};
  const detail::InitialStateProblem<Model, Integrator, Record, Measured, Settings> problem{
      model, integrator, theta, record, measured, sampling, samples, settings};
  return detail::estimateInitialStateWith(problem, guess, settings);
}

}  // namespace mjukf::offline
