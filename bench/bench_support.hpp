#pragma once

// What the step, floor and run benchmarks share: the three filters of a paper experiment, a model
// wrapper that counts its evaluations, and simulated measurements.

#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/paper/experiments.hpp"
#include "mjukf/simulation.hpp"
#include "mjukf/ukf.hpp"

namespace mjukf::bench {

using Tank = paper::CoupledTankExperiment<double>;
using Robot = paper::FlexibleJointExperiment<double>;

template <class Experiment>
const char* plantName() {
  return std::is_same_v<Experiment, Tank> ? "coupled_tank" : "flexible_joint";
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
  typename Base::State derivative(typename Base::Scalar t, const typename Base::State& x,
                                  const typename Base::Input& u, const typename Base::Param& theta) const {
    ++counts->derivative;
    return Base::derivative(t, x, u, theta);
  }
};

// The paper's settings, moved to another model type with the same dimensions.
template <class To, class From>
UkfSettings<To> rebind(const UkfSettings<From>& s) {
  UkfSettings<To> r;
  r.sigmaPoints = s.sigmaPoints;
  r.initialCovariance = s.initialCovariance;
  r.processNoise = s.processNoise;
  r.measurementNoise = s.measurementNoise;
  r.redrawPointsForUpdate = s.redrawPointsForUpdate;
  return r;
}
template <class To, class From>
JointUkfSettings<To> rebind(const JointUkfSettings<From>& s) {
  JointUkfSettings<To> r;
  r.sigmaPoints = s.sigmaPoints;
  r.initialCovariance = s.initialCovariance;
  r.processNoise = s.processNoise;
  r.measurementNoise = s.measurementNoise;
  r.redrawPointsForUpdate = s.redrawPointsForUpdate;
  return r;
}
template <class To, class From>
ModifiedJointUkfSettings<To> rebind(const ModifiedJointUkfSettings<From>& s) {
  ModifiedJointUkfSettings<To> r;
  r.sigmaPoints = s.sigmaPoints;
  r.initialCovariance = s.initialCovariance;
  r.processNoise = s.processNoise;
  r.measurementNoise = s.measurementNoise;
  r.redrawPointsForUpdate = s.redrawPointsForUpdate;
  r.scaling = s.scaling;
  r.transformation = s.transformation;
  r.parameterSpread = s.parameterSpread;
  r.automaticTransformation = s.automaticTransformation;
  r.adaptiveScaling = s.adaptiveScaling;
  r.convergenceTime = s.convergenceTime;
  r.sensitivityInterval = s.sensitivityInterval;
  return r;
}

enum class FilterKind { Ukf, Jukf, Mjukf };

inline const char* filterName(FilterKind kind) {
  return kind == FilterKind::Ukf ? "ukf" : kind == FilterKind::Jukf ? "jukf" : "mjukf";
}

template <FilterKind Kind, class Model>
using FilterType = std::conditional_t<
    Kind == FilterKind::Ukf, Ukf<Model>,
    std::conditional_t<Kind == FilterKind::Jukf, JointUkf<Model>, ModifiedJointUkf<Model>>>;

/// The filter of kind `Kind` with the paper's settings of `Experiment`, on `model` (the plant's model
/// or a counting wrapper of it). The UKF is given the true parameters, the joint filters the first guess.
template <FilterKind Kind, class Experiment, class Model = typename Experiment::Model>
FilterType<Kind, Model> makeFilter(const Model& model = Model()) {
  const auto x0 = Experiment::initialState();
  if constexpr (Kind == FilterKind::Ukf)
    return FilterType<Kind, Model>(model, x0, Experiment::Model::trueParameters(),
                                   rebind<Model>(Experiment::ukf()));
  else if constexpr (Kind == FilterKind::Jukf)
    return FilterType<Kind, Model>(model, x0, Experiment::initialParameters(),
                                   rebind<Model>(Experiment::jointUkf()));
  else
    return FilterType<Kind, Model>(model, x0, Experiment::initialParameters(),
                                   rebind<Model>(Experiment::modifiedJointUkf()));
}

/// Measurements y_k = x(k h) + v_k of the plant with its true parameters, simulated with I-TR-BDF2
/// from the experiment's initial state; v_k is Gaussian with the paper's R. Row 0 is the initial state.
template <class Experiment>
std::vector<typename Experiment::Model::Meas> simulatedMeasurements(long rows) {
  using Model = typename Experiment::Model;
  using State = typename Model::State;
  const Model model;
  const auto theta = Model::trueParameters();
  const double noiseSd = std::sqrt(Experiment::ukf().measurementNoise(0, 0));
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> normal(0.0, noiseSd);
  std::vector<typename Model::Meas> y(static_cast<std::size_t>(rows));
  if (rows < 1) return y;
  simulate(model, ITrBdf2<double>(), Experiment::initialState(), theta, 0.0, Experiment::stepSize, rows - 1,
           [&](long k, double, const State& x) {
             auto& row = y[static_cast<std::size_t>(k)];
             row = model.measurement(x, theta);
             for (int c = 0; c < row.size(); ++c) row(c) += normal(rng);
           });
  return y;
}

}  // namespace mjukf::bench
