#pragma once

/// \file
/// The settings of the two experiments of the 2019 MJUKF paper (the Van der Pol oscillator and the
/// Lorenz system; docs/studies.md): not plants of the paper this library reproduces, but the systems
/// the method was first shown on. The MJUKF settings (x̂₀, θ̂₀, P₀, Q, R, ξ, T, p_θ) are the 2019
/// paper's; JUKF's parameter block of P₀ and Q and the dual UKF are this library's choice (below).
///
/// Both are simulated with RK4 from a true initial state that differs from the filters' x̂₀, and
/// measured every step with y = x + e, e of standard deviation `relativeNoise`·|xᵢ| per component.

#include "mjukf/dual_ukf.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/models/lorenz.hpp"
#include "mjukf/models/van_der_pol.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"

namespace mjukf::paper {

/// Settings every filter of a 2019 experiment shares: the state's P₀, Q and R (`stateP0`, `stateQ`,
/// `r`), JUKF's and the dual's parameter P₀ and Q (`parameterP0`, `parameterQ`).
template <class Model>
struct Settings2019 {
  /// The model's floating-point type.
  using Scalar = typename Model::Scalar;
  /// \var stateP0
  /// The state's initial covariance P₀ = stateP0 · I.
  //
  /// \var stateQ
  /// The state's process noise covariance Q = stateQ · I.
  //
  /// \var r
  /// The measurement noise covariance R = r · I.
  //
  /// \var parameterP0
  /// The parameters' initial covariance, JUKF's θ block of P₀ and the dual's, parameterP0 · I.
  //
  /// \var parameterQ
  /// The parameters' process noise covariance, JUKF's θ block of Q and the dual's, parameterQ · I.
  Scalar stateP0, stateQ, r, parameterP0, parameterQ;

  /// The state-only UKF's settings: P₀, Q and R.
  UkfSettingsFor<Model> ukf() const {
    UkfSettingsFor<Model> s;
    s.initialCovariance.diagonal().setConstant(stateP0);
    s.processNoise.diagonal().setConstant(stateQ);
    s.measurementNoise.diagonal().setConstant(r);
    return s;
  }

  /// JUKF's settings: P₀ and Q with the state's block then the parameters' block, and R.
  JointUkfSettingsFor<Model> jointUkf() const {
    JointUkfSettingsFor<Model> s;
    s.initialCovariance.diagonal() << Eigen::Matrix<Scalar, Model::StateDim, 1>::Constant(stateP0),
        Eigen::Matrix<Scalar, Model::ParamDim, 1>::Constant(parameterP0);
    s.processNoise.diagonal() << Eigen::Matrix<Scalar, Model::StateDim, 1>::Constant(stateQ),
        Eigen::Matrix<Scalar, Model::ParamDim, 1>::Constant(parameterQ);
    s.measurementNoise.diagonal().setConstant(r);
    return s;
  }

  /// ξ, T and p_θ are the caller's (they differ per system).
  ModifiedJointUkfSettingsFor<Model> modifiedJointUkf() const {
    ModifiedJointUkfSettingsFor<Model> s;
    s.initialCovariance.diagonal().setConstant(stateP0);
    s.processNoise.diagonal().setConstant(stateQ);
    s.measurementNoise.diagonal().setConstant(r);
    return s;
  }

  /// The state filter as the UKF's; the parameter filter starts from JUKF's P^θ₀ with Q_θ = 0 (the
  /// parameters are constant) and observes with the state filter's innovation covariance (no extra
  /// parameterObservationNoise).
  DualUkfSettingsFor<Model> dualUkf() const {
    DualUkfSettingsFor<Model> s;
    static_cast<UnscentedSettings<Scalar, Model::StateDim, Model::MeasDim>&>(s) = ukf();
    s.initialParameterCovariance.diagonal().setConstant(parameterP0);
    return s;
  }
};

/// What both 2019 experiments share: RK4, 100 s, a measurement every step, noise of std 0.1 |xᵢ|, an
/// RMSE window that leaves out the first tenth of the run (as the plants' do), and the UKF, JUKF and
/// dual settings made from `Experiment::common()`.
template <class Experiment, class Model_>
struct Experiment2019 {
  /// The system.
  using Model = Model_;
  /// Its floating-point type.
  using Scalar = typename Model::Scalar;
  /// RK4, for the simulation and the filters alike.
  using Integrator = Rk4<Scalar>;
  /// Its state vector.
  using State = typename Model::State;
  /// Its parameter vector.
  using Param = typename Model::Param;
  /// The length of a run (s).
  static constexpr Scalar duration = Scalar(100);
  /// N: one measurement update every N integration steps (every step).
  static constexpr int measurementEvery = 1;
  /// y = x + e, std(eᵢ) = 0.1 |xᵢ|.
  static constexpr Scalar relativeNoise = Scalar(0.1);

  /// The state-only filter, given the true parameters: P₀, Q and R of `Experiment::common()`.
  static UkfSettingsFor<Model> ukf() { return Experiment::common().ukf(); }
  /// JUKF's settings, from `Experiment::common()`.
  static JointUkfSettingsFor<Model> jointUkf() { return Experiment::common().jointUkf(); }
  /// Not in the 2019 paper: the dual UKF's settings, from `Experiment::common()`.
  static DualUkfSettingsFor<Model> dualUkf() { return Experiment::common().dualUkf(); }
};

/// Van der Pol, μ = 0.2: 100 s at h = 0.1 s with RK4 from x₀ = (1.4, 0), a measurement every step;
/// the filters start at x̂₀ = (0, 5), μ̂₀ = 5.
template <class Scalar = double>
struct VanDerPolExperiment : Experiment2019<VanDerPolExperiment<Scalar>, models::VanDerPol<Scalar>> {
  /// What both 2019 experiments share.
  using Base = Experiment2019<VanDerPolExperiment<Scalar>, models::VanDerPol<Scalar>>;
  /// The system, its state vector and its parameter vector.
  using typename Base::Model, typename Base::State, typename Base::Param;
  /// h, the integration step (s).
  static constexpr Scalar stepSize = Scalar(0.1);
  /// The first data row of the RMSE: the first tenth of the run is left out.
  static constexpr long rmseFromRow = 100;  // t ≥ 10 s

  /// x₀ = (1.4, 0), the simulated system's initial state.
  static State trueInitialState() { return State(Scalar(1.4), Scalar(0)); }
  /// x̂₀ = (0, 5), the filters' initial state.
  static State initialState() { return State(Scalar(0), Scalar(5)); }
  /// θ̂₀ = (μ̂₀) = (5), the first guess.
  static Param initialParameters() { return Param::Constant(Scalar(5)); }

  /// P₀ = 5 I, Q = 1e-3 I, R = 0.1 I (2019). JUKF's μ block (this library's choice): P₀ = 5 as the
  /// states' (a prior standard deviation of 2.2 for a guess 4.8 off), Q = 1e-5 as the paper's plants'
  /// JUKF (a constant parameter needs only a slow random walk; docs/studies.md).
  static Settings2019<Model> common() { return {Scalar(5), Scalar(1e-3), Scalar(0.1), Scalar(5), Scalar(1e-5)}; }

  /// ξ = 0.25, T = [0.5 0.5], p_θ = 0.5 (2019).
  static ModifiedJointUkfSettingsFor<Model> modifiedJointUkf() {
    auto s = common().modifiedJointUkf();
    s.scaling = Scalar(0.25);
    s.transformation << Scalar(0.5), Scalar(0.5);
    s.parameterSpread << Scalar(0.5);
    s.followParameterCovariance = false;  // the paper's MJUKF, at the paper's cost
    return s;
  }
};

/// Lorenz, (σ, ρ, β) = (10, 28, 8/3): 100 s at h = 0.01 s with RK4 from x₀ = (0.9, 1, 1.1), a
/// measurement every step; the filters start at x̂₀ = (1.5, 1.5, 1.5), θ̂₀ = (5, 21, 1/3).
template <class Scalar = double>
struct LorenzExperiment : Experiment2019<LorenzExperiment<Scalar>, models::Lorenz<Scalar>> {
  /// What both 2019 experiments share.
  using Base = Experiment2019<LorenzExperiment<Scalar>, models::Lorenz<Scalar>>;
  /// The system, its state vector and its parameter vector.
  using typename Base::Model, typename Base::State, typename Base::Param;
  /// h, the integration step (s).
  static constexpr Scalar stepSize = Scalar(0.01);
  /// The first data row of the RMSE: the first tenth of the run is left out.
  static constexpr long rmseFromRow = 1000;  // t ≥ 10 s

  /// x₀ = (0.9, 1, 1.1), the simulated system's initial state.
  static State trueInitialState() { return State(Scalar(0.9), Scalar(1), Scalar(1.1)); }
  /// x̂₀ = (1.5, 1.5, 1.5), the filters' initial state.
  static State initialState() { return State::Constant(Scalar(1.5)); }
  /// θ̂₀ = (σ̂₀, ρ̂₀, β̂₀) = (5, 21, 1/3), the first guess.
  static Param initialParameters() { return Param(Scalar(5), Scalar(21), Scalar(1) / Scalar(3)); }

  /// P₀ = Q = 1e-3 I, R = 0.2 I (2019). JUKF's θ block (this library's choice): P₀ = 10 I (a prior
  /// standard deviation of 3.2, the size of the guesses' errors 5, 7 and 2.3 within a factor 2),
  /// Q = 1e-5 I as the paper's plants' JUKF (docs/studies.md).
  static Settings2019<Model> common() { return {Scalar(1e-3), Scalar(1e-3), Scalar(0.2), Scalar(10), Scalar(1e-5)}; }

  /// ξ = 0.006, T = [[0.8 0.1 0.1], [0.1 0.8 0.1], [0.1 0.1 0.8]], p_θ = 0.5 (2019).
  static ModifiedJointUkfSettingsFor<Model> modifiedJointUkf() {
    auto s = common().modifiedJointUkf();
    s.scaling = Scalar(0.006);
    s.transformation << Scalar(0.8), Scalar(0.1), Scalar(0.1),  //
        Scalar(0.1), Scalar(0.8), Scalar(0.1),                  //
        Scalar(0.1), Scalar(0.1), Scalar(0.8);
    s.parameterSpread.setConstant(Scalar(0.5));
    s.followParameterCovariance = false;  // the paper's MJUKF, at the paper's cost
    return s;
  }
};

}  // namespace mjukf::paper
