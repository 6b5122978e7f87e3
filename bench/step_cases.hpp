#pragma once

// The three per-step cases that the step benchmarks time and the instruction counter counts, so both
// measure the same code:
//   MeasurementSteps: one measurement step of the paper's schedule, a time update over one integrator
//     step followed by a measurement update, on simulated measurements (in either covariance form);
//   OpenLoopSteps: one open-loop step of the mean (the schedule's steps between measurements);
//   FloorSteps: the model propagations a measurement step cannot avoid, written out by hand: one
//     I-TR-BDF2 step of each of the filter's points (each with the parameters the filter would give
//     it), with the input evaluated once per stage time. step/floor is the filter's own overhead.
// Each case's once() advances it by one step; after `kRows` steps it starts over from its first state.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "bench_support.hpp"

namespace mjukf::bench {

inline constexpr long kRows = 20001;  // 20 s of simulated measurements; a case starts over after them

template <class Experiment>
const std::vector<typename Experiment::Model::Meas>& measurements() {
  static const auto y = simulatedMeasurements<Experiment>(kRows);
  return y;
}

/// Propagations per time update of a filter over one of the paper's models (bench_support.hpp).
template <FilterKind Kind, class Model>
constexpr int pointCount() {
  return propagationsPerUpdate<Kind, FilterType<Kind, Model>, Model::ParamDim>();
}

/// Evaluations of the derivative and the input in one step (a measurement step or an open-loop one),
/// after a few steps to settle, counted on a counting copy of the model.
template <FilterKind Kind, class Experiment>
EvaluationCounts countEvaluations(bool measurementStep) {
  using Scalar = typename Experiment::Model::Scalar;
  EvaluationCounts counts;
  Counting<typename Experiment::Model> model;
  model.counts = &counts;
  auto filter = makeFilter<Kind, Experiment>(model);
  const auto& y = measurements<Experiment>();
  const Scalar h = Experiment::stepSize;
  for (long k = 0; k < 10; ++k) {
    (void)filter.timeUpdate(Scalar(k) * h, h);
    (void)filter.measurementUpdate(y[static_cast<std::size_t>(k + 1)]);
  }
  counts = {};
  if (measurementStep) {
    (void)filter.timeUpdate(Scalar(10) * h, h);
    (void)filter.measurementUpdate(y[11]);
  } else {
    (void)filter.propagateMean(Scalar(10) * h, h);
  }
  return counts;
}

template <FilterKind Kind, class Experiment, class Form = FullCovariance>
class MeasurementSteps {
 public:
  using Scalar = typename Experiment::Model::Scalar;
  MeasurementSteps() : fresh_(makeFilter<Kind, Experiment, typename Experiment::Model, Form>()), filter_(fresh_) {}
  /// One step; false when the filter refused it.
  bool once() {
    if (k_ + 1 == kRows) restart();
    const Scalar h = Experiment::stepSize;
    Status s = filter_.timeUpdate(Scalar(k_) * h, h);
    if (s == Status::Ok) s = filter_.measurementUpdate(measurements<Experiment>()[static_cast<std::size_t>(k_ + 1)]);
    ++k_;
    return s == Status::Ok;
  }
  long row() const { return k_; }
  const auto& filter() const { return filter_; }

 private:
  void restart() {
    filter_ = fresh_;
    k_ = 0;
  }
  FilterType<Kind, typename Experiment::Model, Form> fresh_, filter_;
  long k_ = 0;
};

template <FilterKind Kind, class Experiment>
class OpenLoopSteps {
 public:
  using Scalar = typename Experiment::Model::Scalar;
  OpenLoopSteps() : fresh_(makeFilter<Kind, Experiment>()), filter_(fresh_) {}
  bool once() {
    if (k_ + 1 == kRows) {
      filter_ = fresh_;
      k_ = 0;
    }
    const Scalar h = Experiment::stepSize;
    return filter_.propagateMean(Scalar(k_++) * h, h) == Status::Ok;
  }
  const auto& filter() const { return filter_; }

 private:
  FilterType<Kind, typename Experiment::Model> fresh_, filter_;
  long k_ = 0;
};

template <FilterKind Kind, class Experiment>
class FloorSteps {
 public:
  using Model = typename Experiment::Model;
  using Scalar = typename Model::Scalar;
  using State = typename Model::State;
  using Param = typename Model::Param;
  using Input = typename Model::Input;
  static constexpr int Count = pointCount<Kind, Model>();

  FloorSteps() {
    spreadPoints(measurements<Experiment>()[1000]);
    points_ = start_;
  }

  bool once() {
    if (k_ + 1 == kRows) {
      points_ = start_;
      k_ = 0;
    }
    const Scalar h = Experiment::stepSize;
    const Scalar t = Scalar(k_) * h;
    const Scalar tEnd = t + h;
    // The input at the three stage times of I-TR-BDF2, once for all points.
    const Input u0 = model_.input(t), uGamma = model_.input(t + integrator_.gamma() * h), u1 = model_.input(tEnd);
    for (int i = 0; i < Count; ++i) {
      const Param theta = theta_.col(i);
      const auto f = [&](Scalar time, const State& x) -> State {
        return model_.derivative(time, x, time <= t ? u0 : (time >= tEnd ? u1 : uGamma), theta);
      };
      points_.col(i) = integrator_.step(f, t, State(points_.col(i)), h);
    }
    ++k_;
    return true;
  }
  const Eigen::Matrix<Scalar, Model::StateDim, Count>& points() const { return points_; }

 private:
  // Points spread about a state of the simulated run, with per-point parameters about the truth (all
  // the truth for the UKF, whose points share θ). The dual: its state filter's 2n + 1 points with θ̂
  // (the truth), then its parameter filter's 2p + 1 at that state, each with its θⱼ. The automatic
  // MJUKF: MJUKF's points, then one point per parameter r at x̂ + δ Wᵣ with θ + δ eᵣ.
  void spreadPoints(const State& centre) {
    const Param truth = Model::trueParameters();
    const Scalar step = Scalar(0.01), thetaStep = Kind == FilterKind::Ukf ? Scalar(0) : Scalar(0.001);
    if constexpr (Kind == FilterKind::MjukfAuto) {
      constexpr int points = FilterType<Kind, Model>::SigmaPointCount;
      for (int i = 0; i < points; ++i) {
        start_.col(i) = centre + State::Constant(step * Scalar(i - points / 2));
        theta_.col(i) = truth + Param::Constant(thetaStep * Scalar(i));
      }
      for (int r = 0; r < Model::ParamDim; ++r) {
        start_.col(points + r) = centre + State::Constant(Scalar(1e-6));
        theta_.col(points + r) = truth + Scalar(1e-6) * Param::Unit(r);
      }
    } else if constexpr (Kind == FilterKind::Dual) {
      constexpr int statePoints = FilterType<Kind, Model>::SigmaPointCount;
      for (int i = 0; i < statePoints; ++i) {
        start_.col(i) = centre + State::Constant(step * Scalar(i - statePoints / 2));
        theta_.col(i) = truth;
      }
      for (int j = statePoints; j < Count; ++j) {
        start_.col(j) = centre;
        theta_.col(j) = truth + Param::Constant(thetaStep * Scalar(j - statePoints - (Count - statePoints) / 2));
      }
    } else {
      for (int i = 0; i < Count; ++i) {
        start_.col(i) = centre + State::Constant(step * Scalar(i - Count / 2));
        theta_.col(i) = truth + Param::Constant(thetaStep * Scalar(i));
      }
    }
  }

  const Model model_{};
  const ITrBdf2<Scalar> integrator_{};
  Eigen::Matrix<Scalar, Model::StateDim, Count> start_, points_;
  Eigen::Matrix<Scalar, Model::ParamDim, Count> theta_;
  long k_ = 0;
};

}  // namespace mjukf::bench
