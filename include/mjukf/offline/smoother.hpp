#pragma once

/// \file
/// The unscented Rauch–Tung–Striebel smoother (Särkkä 2008) over a filter's run (offline/run.hpp), for
/// `Ukf` (the state x) and `JointUkf` (the augmented [x; θ]): a host-side tool, docs/offline-tools.md.
/// It needs nothing from the filter's internals: the backward pass redraws the filter's own sigma
/// points from each filtered estimate and propagates them through the filter's model and stepper over
/// the same interval, as the filter's time update did.

#include <type_traits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "mjukf/detail/linear_algebra.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/model.hpp"
#include "mjukf/offline/run.hpp"
#include "mjukf/status.hpp"
#include "mjukf/ukf.hpp"

namespace mjukf::offline {

/// \cond INTERNAL
namespace detail {

// What the smoother smooths for a filter: the vector its sigma points are drawn for (its mean and
// covariance in a Sample) and Φ over one sample for that vector. Defined for Ukf and JointUkf only: the
// other two filters have no covariance of the vector their time update propagates (docs/offline-tools.md).
template <class Filter>
struct SmoothedVector;

template <class M, class I, class P, class F>
struct SmoothedVector<Ukf<M, I, P, F>> {
  using Filter = Ukf<M, I, P, F>;
  static constexpr int Dim = M::StateDim;
  using Vector = Eigen::Matrix<typename M::Scalar, Dim, 1>;
  static Vector mean(const Sample<Filter>& s) { return s.state; }
  // Φ(x; θ) with the fixed parameters.
  template <class Propagate>
  static Vector propagate(const Propagate& phi, const Vector& x, const typename M::Param& theta) {
    return phi(x, theta);
  }
};

template <class M, class I, class P, class F>
struct SmoothedVector<JointUkf<M, I, P, F>> {
  using Filter = JointUkf<M, I, P, F>;
  static constexpr int Dim = M::StateDim + M::ParamDim;
  using Vector = Eigen::Matrix<typename M::Scalar, Dim, 1>;
  static Vector mean(const Sample<Filter>& s) {
    Vector z;
    z << s.state, s.parameters;
    return z;
  }
  // [x; θ] ↦ [Φ(x; θ); θ]: θ constant in the model, as the filter's AugmentedParameters propagate it.
  template <class Propagate>
  static Vector propagate(const Propagate& phi, const Vector& z, const typename M::Param&) {
    Vector next = z;
    next.template head<M::StateDim>() =
        phi(typename M::State(z.template head<M::StateDim>()), typename M::Param(z.template tail<M::ParamDim>()));
    return next;
  }
};

}  // namespace detail
/// \endcond

/// One smoothed sample: the mean and covariance of the filter's estimated vector given every
/// measurement of the data set, at the sample's time t_{k+1}. For `Ukf` the state x; for `JointUkf` the
/// augmented [x; θ] (state() and parameters() split it).
template <class Filter>
struct SmoothedSample {
  /// The dimension of the smoothed vector: n, or n + p for `JointUkf`.
  static constexpr int Dim = detail::SmoothedVector<Filter>::Dim;
  /// The model's floating-point type.
  using Scalar = typename Filter::Scalar;
  /// The smoothed vector.
  using Vector = Eigen::Matrix<Scalar, Dim, 1>;
  /// Its covariance.
  using Matrix = Eigen::Matrix<Scalar, Dim, Dim>;

  Scalar time = 0;                     ///< t_{k+1}, as in the filter's Sample
  Vector mean = Vector::Zero();        ///< the smoothed mean
  Matrix covariance = Matrix::Zero();  ///< the smoothed covariance

  /// The state block x of the mean.
  typename Filter::State state() const { return mean.template head<Filter::StateDim>(); }
  /// The parameter block θ of the mean (`JointUkf` only: `Ukf`'s parameters are fixed, not smoothed).
  template <int D = Dim, std::enable_if_t<(D > Filter::StateDim), int> = 0>
  typename Filter::Param parameters() const {
    return mean.template tail<Filter::ParamDim>();
  }
};

/// What the backward pass did: Ok, or the first refusal and the sample where it happened (the samples
/// from there down to 0 then hold the filtered estimates).
struct SmootherOutcome {
  Status status = Status::Ok;  ///< Ok, NotPositiveDefinite or NonFiniteResult
  long sample = -1;            ///< the sample whose backward step was refused; −1 when none was
  /// True when every sample was smoothed.
  bool ok() const { return status == Status::Ok; }
};

/// The unscented RTS smoother (Särkkä 2008, "Unscented Rauch–Tung–Striebel smoother", IEEE TAC 53(3))
/// of `filtered`, the record of `filter`'s run over `data` (offline/run.hpp), into `smoothed` (resized
/// to the record's length). `filter` is read for its model, stepper and settings only (α β κ and the
/// sigma-point set, Q); its estimate is not used.
///
/// The last sample is the filtered one. For k = N − 2 … 0, with (x_k, P_k) the filtered estimate after
/// sample k and sample k + 1's interval (its time, held input and steps):
///
///     χᵢ = the filter's sigma points of (x_k, P_k),   χᵢ⁺ = Φ(χᵢ) over the interval (all its steps),
///     x⁻ = Σ Wmᵢ χᵢ⁺,   P⁻ = Σ Wcᵢ (χᵢ⁺ − x⁻)(χᵢ⁺ − x⁻)ᵀ + Q   (Q once per time update, as the filter),
///     C = Σ Wcᵢ (χᵢ − x_k)(χᵢ⁺ − x⁻)ᵀ,   G = C (P⁻)⁻¹,
///     x^s_k = x_k + G (x^s_{k+1} − x⁻),   P^s_k = P_k + G (P^s_{k+1} − P⁻) Gᵀ.
///
/// A sample whose time update was refused moved nothing (the filter's estimate stayed where it was), so
/// its backward step is the identity: x^s_k = x^s_{k+1}. The step's P⁻ is the unrepaired one (a filter
/// that repaired its P⁻ on that step committed a slightly larger one; docs/offline-tools.md). Each
/// backward step allocates nothing; only `smoothed` is resized.
template <class Filter>
SmootherOutcome smooth(const Filter& filter, const DataSet<typename Filter::Model>& data,
                       const std::vector<Sample<Filter>>& filtered, std::vector<SmoothedSample<Filter>>& smoothed) {
  using Model = typename Filter::Model;
  using Scalar = typename Model::Scalar;
  using Vec = detail::SmoothedVector<Filter>;
  constexpr int L = Vec::Dim;
  using Vector = Eigen::Matrix<Scalar, L, 1>;
  using Matrix = Eigen::Matrix<Scalar, L, L>;
  using SigmaPoints = typename Filter::SigmaPoints;
  static_assert(SigmaPoints::Dim == L, "the smoother draws the filter's own sigma points");
  using Points = typename SigmaPoints::Points;

  const long n = static_cast<long>(filtered.size());
  smoothed.resize(static_cast<std::size_t>(n));
  for (long k = 0; k < n; ++k) {
    smoothed[k].time = filtered[k].time;
    smoothed[k].mean = Vec::mean(filtered[k]);
    smoothed[k].covariance = filtered[k].covariance;
  }
  SigmaPoints sigmaPoints(mjukf::detail::Validated{}, filter.settings().sigmaPoints);  // validated by the filter
  const Matrix& processNoise = filter.settings().processNoise;
  const auto& weightsMean = sigmaPoints.meanWeights();
  const auto& weightsCov = sigmaPoints.covarianceWeights();
  Points drawn, propagated, drawnDeviations, propagatedDeviations;
  Vector predictedMean;
  Matrix predictedCovariance, cross, gain;
  Eigen::LLT<Matrix> predictedFactor;

  for (long k = n - 2; k >= 0; --k) {
    const long next = k + 1;  // the sample whose time update leads from k to k + 1
    if (!taken(filtered[next].timeUpdate)) {
      smoothed[k].mean = smoothed[next].mean;
      smoothed[k].covariance = smoothed[next].covariance;
      continue;
    }
    const Vector mean = smoothed[k].mean;              // still the filtered x_k
    const Matrix covariance = smoothed[k].covariance;  // and P_k
    if (sigmaPoints.generate(mean, covariance, drawn) != Status::Ok) return {Status::NotPositiveDefinite, k};
    // Φ over sample next's interval, with its held input or the model's own input(t), as runSample's
    // time update; θ the filter's fixed parameters (Ukf) or each point's own θ block (JointUkf).
    const Scalar t = data.sampleTime(next);
    const auto phi = [&](const typename Model::State& x, const typename Model::Param& theta) {
      typename Model::State state = x;
      for (int s = 0; s < data.stepsPerSample; ++s) {
        const Scalar ts = t + Scalar(s) * data.stepSize;
        if (data.inputs)
          state = stepModel(filter.model(), filter.integrator(), ts, data.stepSize, state, data.inputs[next], theta);
        else if constexpr (needsNoInputArgument<Model>)  // otherwise the time update was refused: not here
          state = stepModel(filter.model(), filter.integrator(), ts, data.stepSize, state, theta);
      }
      return state;
    };
    for (int i = 0; i < SigmaPoints::Count; ++i)
      propagated.col(i) = Vec::propagate(phi, Vector(drawn.col(i)), filtered[k].parameters);
    if (!mjukf::detail::allFinite(propagated)) return {Status::NonFiniteResult, k};

    mjukf::detail::weightedMean(propagated, weightsMean, predictedMean);
    mjukf::detail::deviationsFrom(propagated, predictedMean, propagatedDeviations);
    mjukf::detail::deviationsFrom(drawn, mean, drawnDeviations);
    mjukf::detail::weightedOuterSum(propagatedDeviations, propagatedDeviations, weightsCov, predictedCovariance);
    predictedCovariance += processNoise;
    mjukf::detail::symmetrize(predictedCovariance);
    mjukf::detail::weightedOuterSum(drawnDeviations, propagatedDeviations, weightsCov, cross);
    predictedFactor.compute(predictedCovariance);
    if (predictedFactor.info() != Eigen::Success) return {Status::NotPositiveDefinite, k};
    gain = predictedFactor.solve(cross.transpose()).transpose();  // G = C (P⁻)⁻¹, P⁻ symmetric

    smoothed[k].mean = mean + gain * (smoothed[next].mean - predictedMean);
    smoothed[k].covariance = covariance + gain * (smoothed[next].covariance - predictedCovariance) * gain.transpose();
    mjukf::detail::symmetrize(smoothed[k].covariance);
    if (!mjukf::detail::allFinite(smoothed[k].mean) || !mjukf::detail::allFinite(smoothed[k].covariance))
      return {Status::NonFiniteResult, k};
  }
  return {};
}

}  // namespace mjukf::offline
