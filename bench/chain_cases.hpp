#pragma once

// The chain's two per-step cases (chain_model.hpp), shared by the scaling benchmark, which times them,
// and the instruction counter, which counts them, so that both measure the same code:
//   ChainSteps: one measurement step, a time update over 1 ms (one RK4 step, or `Steps` steps of
//     1/Steps ms: a subdivided update), then a measurement update;
//   ChainFloorSteps: its floor, as step_cases.hpp's FloorSteps: the filter's points, one RK4 step each
//     with the parameters the filter would give it, the input evaluated once per stage time.
// Each once() advances its case by one step; after kChainRows steps it starts over. The filters and the
// points live on the heap (a filter is 152–192 KB at n = 32).

#include <cstddef>
#include <memory>
#include <random>
#include <type_traits>
#include <vector>

#include "bench_support.hpp"
#include "chain_model.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/simulation.hpp"

namespace mjukf::bench {

inline constexpr long kChainRows = 5001;  // 5 s of measurements; a case starts over after them

template <FilterKind Kind, class Model>
using ChainFilter = std::conditional_t<
    Kind == FilterKind::Ukf, Ukf<Model, Rk4<typename Model::Scalar>>,
    std::conditional_t<Kind == FilterKind::Jukf, JointUkf<Model, Rk4<typename Model::Scalar>>,
                       std::conditional_t<Kind == FilterKind::Dual, DualUkf<Model, Rk4<typename Model::Scalar>>,
                                          ModifiedJointUkf<Model, Rk4<typename Model::Scalar>>>>>;

template <FilterKind Kind, class Model>
std::unique_ptr<ChainFilter<Kind, Model>> makeChainFilter() {
  using E = ChainExperiment<Model>;
  using Filter = ChainFilter<Kind, Model>;
  const Model model;
  if constexpr (Kind == FilterKind::Ukf)
    return std::make_unique<Filter>(model, E::initialState(), Model::trueParameters(), E::ukf());
  else if constexpr (Kind == FilterKind::Jukf)
    return std::make_unique<Filter>(model, E::initialState(), E::initialParameters(), E::jointUkf());
  else if constexpr (Kind == FilterKind::Dual)
    return std::make_unique<Filter>(model, E::initialState(), E::initialParameters(), E::dualUkf());
  else
    return std::make_unique<Filter>(model, E::initialState(), E::initialParameters(),
                                    E::modifiedJointUkf(Kind == FilterKind::MjukfAuto));
}

// y_k = x(k h) + v_k with the true parameters, RK4 from rest; v_k Gaussian with R's variance.
template <class Model>
const std::vector<typename Model::Meas>& chainMeasurements() {
  static const auto y = [] {
    using Scalar = typename Model::Scalar;
    const Model model;
    const auto theta = Model::trueParameters();
    std::mt19937_64 rng(2024);
    std::normal_distribution<double> normal(0.0, 1e-2);
    std::vector<typename Model::Meas> rows(static_cast<std::size_t>(kChainRows));
    simulate(model, Rk4<Scalar>(), Model::State::Zero().eval(), theta, Scalar(0), ChainExperiment<Model>::stepSize,
             kChainRows - 1, [&](long k, Scalar, const typename Model::State& x) {
               auto& row = rows[static_cast<std::size_t>(k)];
               row = model.measurement(x, theta);
               for (int c = 0; c < row.size(); ++c) row(c) += Scalar(normal(rng));
             });
    return rows;
  }();
  return y;
}

/// Propagations per time update of a filter over the chain (bench_support.hpp).
template <FilterKind Kind, class Model>
constexpr int chainPointCount() {
  return propagationsPerUpdate<Kind, ChainFilter<Kind, Model>, Model::ParamDim>();
}

template <FilterKind Kind, class Model, int Steps = 1>
class ChainSteps {
 public:
  using Scalar = typename Model::Scalar;
  ChainSteps() : fresh_(makeChainFilter<Kind, Model>()), filter_(makeChainFilter<Kind, Model>()) {}
  /// One step; false when the filter refused it.
  bool once() {
    if (k_ + 1 == kChainRows) {
      *filter_ = *fresh_;
      k_ = 0;
    }
    const Scalar h = ChainExperiment<Model>::stepSize;
    Status s = filter_->timeUpdate(Scalar(k_) * h, h / Scalar(Steps), Steps);
    if (s == Status::Ok) s = filter_->measurementUpdate(chainMeasurements<Model>()[static_cast<std::size_t>(k_ + 1)]);
    ++k_;
    return s == Status::Ok;
  }
  long row() const { return k_; }
  const ChainFilter<Kind, Model>& filter() const { return *filter_; }

 private:
  std::unique_ptr<ChainFilter<Kind, Model>> fresh_, filter_;
  long k_ = 0;
};

// The floor's points are spread about a state of the simulated run: the state filter's points by 0.01
// per point, the extra ones (the dual's parameter points, the automatic MJUKF's differences) at the
// centre, each point's θ 0.001 apart (all the truth for the UKF, whose points share θ).
template <FilterKind Kind, class Model>
class ChainFloorSteps {
 public:
  using Scalar = typename Model::Scalar;
  using State = typename Model::State;
  using Param = typename Model::Param;
  using Input = typename Model::Input;
  static constexpr int Count = chainPointCount<Kind, Model>();
  using Points = Eigen::Matrix<Scalar, Model::StateDim, Count>;
  using Thetas = Eigen::Matrix<Scalar, Model::ParamDim, Count>;

  ChainFloorSteps()
      : start_(std::make_unique<Points>()), points_(std::make_unique<Points>()), thetas_(std::make_unique<Thetas>()) {
    constexpr int statePoints = ChainFilter<Kind, Model>::SigmaPointCount;
    State centre = State::Zero();
    centre.template head<Model::MeasDim>() = chainMeasurements<Model>()[1000];
    const Param truth = Model::trueParameters();
    const Scalar step = Scalar(0.01), thetaStep = Kind == FilterKind::Ukf ? Scalar(0) : Scalar(0.001);
    for (int i = 0; i < Count; ++i) {
      const bool extra = i >= statePoints;
      start_->col(i) = extra ? centre : State(centre + State::Constant(step * Scalar(i - statePoints / 2)));
      thetas_->col(i) = truth + Param::Constant(thetaStep * Scalar(extra ? i - statePoints : i));
    }
    *points_ = *start_;
  }

  bool once() {
    if (k_ + 1 == kChainRows) {
      *points_ = *start_;
      k_ = 0;
    }
    const Scalar h = ChainExperiment<Model>::stepSize;
    const Scalar t = Scalar(k_) * h, tEnd = t + h;
    const Input u0 = model_.input(t), uHalf = model_.input(t + h / Scalar(2)), u1 = model_.input(tEnd);
    for (int i = 0; i < Count; ++i) {
      const Param theta = thetas_->col(i);
      const auto f = [&](Scalar time, const State& x) -> State {
        return model_.derivative(time, x, time <= t ? u0 : (time >= tEnd ? u1 : uHalf), theta);
      };
      points_->col(i) = integrator_.step(f, t, State(points_->col(i)), h);
    }
    ++k_;
    return true;
  }
  const Points& points() const { return *points_; }

 private:
  const Model model_{};
  const Rk4<Scalar> integrator_{};
  std::unique_ptr<Points> start_, points_;
  std::unique_ptr<Thetas> thetas_;
  long k_ = 0;
};

}  // namespace mjukf::bench
