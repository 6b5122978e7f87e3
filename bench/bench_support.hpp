#pragma once

// What the step, floor and run benchmarks share: the three filters of a paper experiment, a model
// wrapper that counts its evaluations, and simulated measurements.

#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "mjukf/dual_ukf.hpp"
#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/simulation.hpp"
#include "mjukf/ukf.hpp"
#include "paper/experiments.hpp"

namespace mjukf::bench {

template <class Scalar = double>
using TankOf = paper::CoupledTankExperiment<Scalar>;
template <class Scalar = double>
using RobotOf = paper::FlexibleJointExperiment<Scalar>;
using Tank = TankOf<double>;
using Robot = RobotOf<double>;

template <class Experiment>
const char* plantName() {
  return std::is_same_v<Experiment, TankOf<typename Experiment::Model::Scalar>> ? "coupled_tank" : "flexible_joint";
}

template <class Scalar>
const char* scalarName() {
  return std::is_same_v<Scalar, float> ? "float" : "double";
}

/// How often a model was evaluated, through a pointer so the count survives the copy a filter keeps.
struct EvaluationCounts {
  long derivative = 0;
  long input = 0;
};

/// `Base` with every derivative and input evaluation counted; used only to measure the counters,
/// never in a timed loop.
template <class Base>
struct Counting : Base {
  EvaluationCounts* counts = nullptr;
  typename Base::Input input(typename Base::Scalar t) const {
    ++counts->input;
    return Base::input(t);
  }
  typename Base::State derivative(typename Base::Scalar t, const typename Base::State& x, const typename Base::Input& u,
                                  const typename Base::Param& theta) const {
    ++counts->derivative;
    return Base::derivative(t, x, u, theta);
  }
};

/// ukf, jukf, mjukf: the paper's settings; mjukf_auto: MJUKF with both automatic modes (T from the
/// sensitivities, adaptive ξ; docs/tuning-mjukf.md) and the paper's other settings; dual: the dual UKF
/// with the library's settings (Experiment::dualUkf(), PriorParameters ordering; the paper runs none).
enum class FilterKind { Ukf, Jukf, Mjukf, MjukfAuto, Dual };

inline const char* filterName(FilterKind kind) {
  switch (kind) {
    case FilterKind::Ukf: return "ukf";
    case FilterKind::Jukf: return "jukf";
    case FilterKind::Mjukf: return "mjukf";
    case FilterKind::MjukfAuto: return "mjukf_auto";
    case FilterKind::Dual: return "dual";
  }
  return "?";
}

/// Propagations per time update of a filter of kind `Kind` (its type `Filter`) whose model has
/// `ParamDim` parameters: its sigma points; the dual's are its two filters', (2n + 1) + (2p + 1); the
/// automatic MJUKF adds the p forward differences of its sensitivities.
template <FilterKind Kind, class Filter, int ParamDim>
constexpr int propagationsPerUpdate() {
  if constexpr (Kind == FilterKind::Dual)
    return Filter::SigmaPointCount + Filter::ParameterSigmaPointCount;
  else if constexpr (Kind == FilterKind::MjukfAuto)
    return Filter::SigmaPointCount + ParamDim;
  else
    return Filter::SigmaPointCount;
}

/// The filter of kind `Kind` over `Model`, with the default stepper and sigma points, in the covariance
/// form `Form` (covariance_form.hpp).
template <FilterKind Kind, class Model, class Form = FullCovariance>
using FilterType = std::conditional_t<
    Kind == FilterKind::Ukf, Ukf<Model, DefaultIntegrator<Model>, MerweScaled, Form>,
    std::conditional_t<Kind == FilterKind::Jukf, JointUkf<Model, DefaultIntegrator<Model>, MerweScaled, Form>,
                       std::conditional_t<Kind == FilterKind::Mjukf || Kind == FilterKind::MjukfAuto,
                                          ModifiedJointUkf<Model, DefaultIntegrator<Model>, MerweScaled, Form>,
                                          DualUkf<Model, DefaultIntegrator<Model>, MerweScaled, Form>>>>;

/// The filter of kind `Kind` with the settings of `Experiment`, on `model` (the plant's model or a
/// counting wrapper of it). The UKF is given the true parameters, the others the first guess.
template <FilterKind Kind, class Experiment, class Model = typename Experiment::Model, class Form = FullCovariance>
FilterType<Kind, Model, Form> makeFilter(const Model& model = Model()) {
  using Filter = FilterType<Kind, Model, Form>;
  const auto x0 = Experiment::initialState();
  if constexpr (Kind == FilterKind::Ukf)
    return Filter(model, x0, Experiment::Model::trueParameters(), Experiment::ukf());
  else if constexpr (Kind == FilterKind::Jukf)
    return Filter(model, x0, Experiment::initialParameters(), Experiment::jointUkf());
  else if constexpr (Kind == FilterKind::Mjukf)
    return Filter(model, x0, Experiment::initialParameters(), Experiment::modifiedJointUkf());
  else if constexpr (Kind == FilterKind::MjukfAuto) {
    auto settings = Experiment::modifiedJointUkf();
    settings.automaticTransformation = true;
    settings.adaptiveScaling = true;
    return Filter(model, x0, Experiment::initialParameters(), settings);
  } else
    return Filter(model, x0, Experiment::initialParameters(), Experiment::dualUkf());
}

/// Measurements y_k = x(k h) + v_k of the plant with its true parameters, simulated with I-TR-BDF2
/// from the experiment's initial state; v_k is Gaussian with the paper's R. Row 0 is the initial state.
/// The same noise draws (in double) for either scalar type.
template <class Experiment>
std::vector<typename Experiment::Model::Meas> simulatedMeasurements(long rows) {
  using Model = typename Experiment::Model;
  using Scalar = typename Model::Scalar;
  using State = typename Model::State;
  const Model model;
  const auto theta = Model::trueParameters();
  const double noiseSd = std::sqrt(double(Experiment::ukf().measurementNoise(0, 0)));
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> normal(0.0, noiseSd);
  std::vector<typename Model::Meas> y(static_cast<std::size_t>(rows));
  if (rows < 1) return y;
  simulate(model, ITrBdf2<Scalar>(), Experiment::initialState(), theta, Scalar(0), Experiment::stepSize, rows - 1,
           [&](long k, Scalar, const State& x) {
             auto& row = y[static_cast<std::size_t>(k)];
             row = model.measurement(x, theta);
             for (int c = 0; c < row.size(); ++c) row(c) += Scalar(normal(rng));
           });
  return y;
}

}  // namespace mjukf::bench
