#pragma once

/// \file
/// The log-likelihood of a recorded data set under a filter (its settings and parameters), from the
/// innovations of its run (offline/run.hpp): a host-side tool, docs/offline-tools.md.

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "mjukf/detail/linear_algebra.hpp"
#include "mjukf/diagnostics.hpp"
#include "mjukf/offline/run.hpp"
#include "mjukf/settings_error.hpp"
#include "mjukf/status.hpp"
#include "mjukf/ukf.hpp"

namespace mjukf::offline {

/// The log-likelihood of a data set under a filter, and what it is made of.
template <class Scalar>
struct LogLikelihood {
  /// Σ ℓ_k over the measurement updates taken; −∞ when a step was refused for any reason but the gate
  /// (`status`), or when the filter could not be built (`error`).
  Scalar value = 0;
  /// The measurement updates that contributed (one or more components present).
  long terms = 0;
  /// The measured components they contributed, Σ m_k: the degrees of freedom of the sum.
  long components = 0;
  /// Measurement updates the gate refused (`Status::MeasurementRejected`): left out of the sum.
  long rejected = 0;
  /// Ok, or the first refusal other than the gate's (then value = −∞).
  Status status = Status::Ok;
  /// The sample of that refusal; −1 when none.
  long failedSample = -1;
  /// The settings error when the filter could not be built (value = −∞); none otherwise.
  SettingsError error;
  /// True when every step was taken or gated and the filter was built.
  bool ok() const { return status == Status::Ok && !error; }
};

/// ℓ = −½ (m log 2π + log det S + νᵀ S⁻¹ ν) of one measurement update's diagnostics (diagnostics.hpp),
/// over its `presentComponents` = m present components: ν the innovation, S = P_yy. A masked update's
/// diagnostics hold zero innovation and an identity row and column of P_yy for each missing component,
/// so that log det and the NIS of the whole matrix are those of the reduced update. Returns −∞ when
/// P_yy has no Cholesky factor; 0 when nothing was present.
template <class Scalar, int MeasDim>
Scalar logLikelihoodTerm(const UpdateDiagnostics<Scalar, MeasDim>& d, int presentComponents) {
  if (presentComponents == 0) return Scalar(0);
  Eigen::Matrix<Scalar, MeasDim, MeasDim> factor;
  if (!mjukf::detail::choleskyLower(d.innovationCovariance, factor)) return -std::numeric_limits<Scalar>::infinity();
  const Scalar logDet = Scalar(2) * factor.diagonal().array().log().sum();
  const Scalar log2Pi = std::log(Scalar(2) * Scalar(EIGEN_PI));
  return Scalar(-0.5) * (Scalar(presentComponents) * log2Pi + logDet + d.nis);
}

/// Adds sample k of a run (offline/run.hpp) to `sum`: its term when its measurement update was taken,
/// nothing when nothing was present, a count when the gate refused it, −∞ on any other refusal.
template <class Scalar, class Filter>
void accumulate(LogLikelihood<Scalar>& sum, long k, const Sample<Filter>& sample) {
  if (!sum.ok()) return;
  if (sample.measurementUpdate == Status::MeasurementRejected) {
    ++sum.rejected;
    return;
  }
  const Status refused = !taken(sample.timeUpdate) ? sample.timeUpdate : sample.measurementUpdate;
  if (!taken(refused)) {
    sum.status = refused;
    sum.failedSample = k;
    sum.value = -std::numeric_limits<Scalar>::infinity();
    return;
  }
  if (sample.measuredComponents == 0) return;
  sum.value += logLikelihoodTerm(sample.diagnostics, sample.measuredComponents);
  ++sum.terms;
  sum.components += sample.measuredComponents;
}

/// The log-likelihood of `data` under `filter`, run from where it is over every sample (the filter is
/// left after the last): Σ ℓ_k over the measurement updates taken, each over its present components
/// (logLikelihoodTerm). Missing samples (no component present) contribute nothing; gated ones are
/// counted and left out; any other refusal makes it −∞. Allocates nothing.
template <class Filter>
LogLikelihood<typename Filter::Scalar> logLikelihood(Filter& filter, const DataSet<typename Filter::Model>& data) {
  LogLikelihood<typename Filter::Scalar> sum;
  run(filter, data, [&sum](long k, const Sample<Filter>& sample) { accumulate(sum, k, sample); });
  return sum;
}

/// The log-likelihood of `data` under the model with the parameter vector θ = `parameters`, known: a
/// `Ukf<Model, Integrator>` built from (x̂₀, θ, settings) with `create` (no exceptions) and run over the
/// data. For scoring parameter vectors (a grid, an optimiser). An invalid setting or θ gives −∞ and the
/// error.
template <class Model, class Integrator = DefaultIntegrator<Model>>
LogLikelihood<typename Model::Scalar> logLikelihood(const Model& model, const typename Model::Param& parameters,
                                                    const typename Model::State& initialState,
                                                    const UkfSettingsFor<Model>& settings, const DataSet<Model>& data,
                                                    const Integrator& integrator = Integrator()) {
  auto filter = Ukf<Model, Integrator>::create(model, initialState, parameters, settings, integrator);
  if (!filter) {
    LogLikelihood<typename Model::Scalar> failed;
    failed.error = filter.error();
    failed.value = -std::numeric_limits<typename Model::Scalar>::infinity();
    return failed;
  }
  return logLikelihood(*filter, data);
}

}  // namespace mjukf::offline
