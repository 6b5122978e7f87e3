#pragma once

/// \file
/// The experiments of the gallery (docs/studies.md, "The gallery"): five plants of the library's own
/// design, not made for its filters, each run with filter settings made by one rule from what a user
/// would know of the plant, never tuned per plant:
///
/// - R: the true measurement noise variance, diag(σᵢ²) of `noiseStandardDeviation()`.
/// - The state's P₀: diag of the square of the stated initial uncertainty of each state
///   (`initialUncertainty()`, reasoned per plant).
/// - The state's Q: `kStateNoiseFraction` × the square of each state's typical size (`typicalSize()`, the
///   magnitude it takes over the run), per measurement interval.
/// - θ̂₀: the truth times `kFirstGuessFactors` (2 for the first parameter, ½ for the second).
/// - JUKF's and the dual's parameter P₀ = diag(θ̂₀²), each parameter known to within its own size, and
///   Q_θ = `kParameterNoiseFraction` × diag(θ̂₀²) per measurement interval; the dual observes with R
///   alone.
/// - MJUKF: the state's P₀, Q and R, and only `automaticTransformation = true` and
///   `adaptiveScaling = true` on top (no ξ, T, p_θ or convergenceTime set). Both of the `study`
///   subcommand's MJUKF filters, `mjukf` and `mjukf-auto`, are this automatic preset: a hand-tuned
///   MJUKF has no meaning for the gallery.
/// - The UKF (estimating no parameters) takes the state's settings.
/// - Every filter that estimates θ bounds it below by 0 (`parameterBounds.lower`): each gallery
///   parameter is a physical magnitude (a gain, a friction, a resistance, a rate, a conductance), and a
///   user knows its sign. An estimate held at 0 raises the health monitor's ParameterAtBound.
///
/// α, β, κ are the library's defaults everywhere. The simulated plant has no process noise; its
/// measurements carry white Gaussian noise of the stated standard deviation.

#include "mjukf/dual_ukf.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/models/dc_motor.hpp"
#include "mjukf/models/heated_block.hpp"
#include "mjukf/models/lotka_volterra.hpp"
#include "mjukf/models/michaelis_menten.hpp"
#include "mjukf/models/thevenin_battery.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"

namespace mjukf::gallery {

/// Q of the states: this fraction of each state's typical size squared, per measurement interval.
inline constexpr double kStateNoiseFraction = 1e-7;
/// Q_θ of JUKF and the dual: this fraction of θ̂₀ᵢ² per measurement interval.
inline constexpr double kParameterNoiseFraction = 1e-8;
/// θ̂₀ = the truth times these: the first parameter guessed twice too large, the second half too small
/// (every gallery plant has two parameters).
inline constexpr double kFirstGuessFactors[2] = {2.0, 0.5};

/// The settings rule above, for an experiment `Derived` that gives the plant's facts: `stepSize`,
/// `duration`, `measurementEvery`, `rmseFromRow` (the first tenth of the run left out),
/// `trueInitialState()`, `initialState()` (x̂₀), `initialUncertainty()`, `typicalSize()` and
/// `noiseStandardDeviation()`, and optionally `using Integrator` (I-TR-BDF2 otherwise).
template <class Derived, class Model_>
struct GalleryExperiment {
  /// The plant.
  using Model = Model_;
  /// Its floating-point type.
  using Scalar = typename Model::Scalar;
  /// Its state vector.
  using State = typename Model::State;
  /// Its parameter vector.
  using Param = typename Model::Param;
  /// Its measurement vector.
  using Meas = typename Model::Meas;
  static_assert(Model::ParamDim == 2, "the gallery's first-guess rule is written for two parameters");

  /// θ̂₀: the truth times kFirstGuessFactors.
  static Param initialParameters() {
    Param guess = Model::trueParameters();
    for (int i = 0; i < Model::ParamDim; ++i) guess(i) *= Scalar(kFirstGuessFactors[i]);
    return guess;
  }

  /// The state-only filter: the state's P₀, Q and R.
  static UkfSettingsFor<Model> ukf() {
    UkfSettingsFor<Model> s;
    setStateCovariances(s);
    return s;
  }

  /// JUKF: P₀ and Q with the state's block, then the parameters' (diag(θ̂₀²) and its fraction); R.
  static JointUkfSettingsFor<Model> jointUkf() {
    JointUkfSettingsFor<Model> s;
    s.initialCovariance.diagonal() << stateInitialVariance(), parameterInitialVariance();
    s.processNoise.diagonal() << stateProcessNoise(), Scalar(kParameterNoiseFraction) * parameterInitialVariance();
    s.measurementNoise.diagonal() = measurementVariance();
    s.parameterBounds.lower.setZero();  // θ ≥ 0
    return s;
  }

  /// MJUKF automatic: the state's P₀, Q and R, the automatic T and the adaptive ξ, nothing else.
  static ModifiedJointUkfSettingsFor<Model> modifiedJointUkf() {
    ModifiedJointUkfSettingsFor<Model> s;
    setStateCovariances(s);
    s.automaticTransformation = true;
    s.adaptiveScaling = true;
    s.parameterBounds.lower.setZero();  // θ ≥ 0
    return s;
  }

  /// The dual UKF: the state filter as the UKF's, the parameter filter with JUKF's θ block, observing
  /// with R alone.
  static DualUkfSettingsFor<Model> dualUkf() {
    DualUkfSettingsFor<Model> s;
    setStateCovariances(s);
    s.initialParameterCovariance.diagonal() = parameterInitialVariance();
    s.parameterProcessNoise.diagonal() = Scalar(kParameterNoiseFraction) * parameterInitialVariance();
    s.parameterBounds.lower.setZero();  // θ ≥ 0
    return s;
  }

 private:
  static State stateInitialVariance() { return Derived::initialUncertainty().array().square().matrix(); }
  static State stateProcessNoise() {
    return Scalar(kStateNoiseFraction) * Derived::typicalSize().array().square().matrix();
  }
  static Meas measurementVariance() { return Derived::noiseStandardDeviation().array().square().matrix(); }
  static Param parameterInitialVariance() { return initialParameters().array().square().matrix(); }

  template <class Settings>
  static void setStateCovariances(Settings& s) {
    s.initialCovariance.diagonal() = stateInitialVariance();
    s.processNoise.diagonal() = stateProcessNoise();
    s.measurementNoise.diagonal() = measurementVariance();
  }
};

/// The DC motor measured by its angle (models/dc_motor.hpp): 20 s at h = 1 ms, an encoder reading every
/// 5 ms (noise 5 mrad), from rest with the encoder zeroed.
template <class Scalar = double>
struct DcMotorExperiment : GalleryExperiment<DcMotorExperiment<Scalar>, models::DcMotor<Scalar>> {
  /// The plant's vectors.
  using State = typename models::DcMotor<Scalar>::State;
  /// The measurement vector.
  using Meas = typename models::DcMotor<Scalar>::Meas;
  /// h (s).
  static constexpr Scalar stepSize = Scalar(1e-3);
  /// The length of a run (s): ten periods of the voltage.
  static constexpr Scalar duration = Scalar(20);
  /// A measurement every 5 steps (5 ms).
  static constexpr int measurementEvery = 5;
  /// The RMSE leaves out the first tenth of the run.
  static constexpr long rmseFromRow = 2000;  // t ≥ 2 s

  /// At rest, encoder zeroed: x₀ = (0, 0).
  static State trueInitialState() { return State::Zero(); }
  /// x̂₀ = x₀.
  static State initialState() { return State::Zero(); }
  /// Known at rest: 0.01 rad (twice the encoder noise) and 0.1 rad/s.
  static State initialUncertainty() { return State(Scalar(0.01), Scalar(0.1)); }
  /// θ moves between 0 and 40 rad, |ω| reaches 108 rad/s.
  static State typicalSize() { return State(Scalar(50), Scalar(100)); }
  /// An encoder of 5 mrad (about 1000 lines per turn, with interpolation).
  static Meas noiseStandardDeviation() { return Meas::Constant(Scalar(0.005)); }
};

/// The battery (models/thevenin_battery.hpp), in discrete time: one hour at 1 s samples of the
/// terminal voltage (noise 2 mV), from a rested cell at 90% charge guessed at 80%.
template <class Scalar = double>
struct BatteryExperiment : GalleryExperiment<BatteryExperiment<Scalar>, models::TheveninBattery<Scalar>> {
  /// The plant's vectors.
  using State = typename models::TheveninBattery<Scalar>::State;
  /// The measurement vector.
  using Meas = typename models::TheveninBattery<Scalar>::Meas;
  /// The sample time dt (s).
  static constexpr Scalar stepSize = Scalar(1);
  /// One hour (s).
  static constexpr Scalar duration = Scalar(3600);
  /// A measurement every sample.
  static constexpr int measurementEvery = 1;
  /// The RMSE leaves out the first tenth of the run.
  static constexpr long rmseFromRow = 360;  // t ≥ 360 s

  /// A rested cell at 90% charge: x₀ = (0.9, 0).
  static State trueInitialState() { return State(Scalar(0.9), Scalar(0)); }
  /// x̂₀ = (0.8, 0): the charge as a coulomb count of the last use left it, 10 points low.
  static State initialState() { return State(Scalar(0.8), Scalar(0)); }
  /// The charge to within 0.1 (a coulomb count drifts); v₁ to 10 mV (the cell has rested).
  static State initialUncertainty() { return State(Scalar(0.1), Scalar(0.01)); }
  /// z is of order 1, v₁ reaches R₁ × 5 A = 0.15 V.
  static State typicalSize() { return State(Scalar(1), Scalar(0.15)); }
  /// A voltage sensor of 2 mV.
  static Meas noiseStandardDeviation() { return Meas::Constant(Scalar(0.002)); }
};

/// Predator and prey (models/lotka_volterra.hpp): 100 years (nine cycles) with RK4 at h = 0.1 year, a
/// prey count every step (noise 0.3 thousand), the predators guessed 2.5 times too few.
///
/// One step per count: the schedule propagates the covariance over the last step of an interval only
/// (paper/schedule.hpp), and with 10 steps of 0.01 year per count JUKF refused a step on seeds 1–3 even
/// from the true θ and x₀ (its parameter–state correlations grew over a tenth of the interval the states
/// moved over).
template <class Scalar = double>
struct PredatorPreyExperiment : GalleryExperiment<PredatorPreyExperiment<Scalar>, models::LotkaVolterra<Scalar>> {
  /// The plant's vectors.
  using State = typename models::LotkaVolterra<Scalar>::State;
  /// The measurement vector.
  using Meas = typename models::LotkaVolterra<Scalar>::Meas;
  /// RK4, for the simulation and the filters: the cycles are neutrally stable, and the first-order
  /// I-TR-BDF2 spirals out of them (on ẋ = iωx a step multiplies the amplitude by |1 + iωh/2|² =
  /// 1 + (ωh)²/4, 2.3 times at ω ≈ 0.58 /year over this run), where RK4 changes it by about (ωh)⁶/144
  /// per step.
  using Integrator = Rk4<Scalar>;
  /// h (years).
  static constexpr Scalar stepSize = Scalar(0.1);
  /// 100 years: about nine cycles of 10.8 years.
  static constexpr Scalar duration = Scalar(100);
  /// A count every step (0.1 year).
  static constexpr int measurementEvery = 1;
  /// The RMSE leaves out the first tenth of the run.
  static constexpr long rmseFromRow = 100;  // t ≥ 10 years

  /// x₀ = (10, 5) thousand: a wide cycle, the prey between 0.5 and 14, the predators between 0.9 and 6.2.
  static State trueInitialState() { return State(Scalar(10), Scalar(5)); }
  /// x̂₀ = (10, 2): the prey as counted, the predators 2.5 times too few.
  static State initialState() { return State(Scalar(10), Scalar(2)); }
  /// The prey to within 1 thousand (a count); of the predators only the order of magnitude, 5 thousand.
  static State initialUncertainty() { return State(Scalar(1), Scalar(5)); }
  /// The prey of order 10 thousand, the predators 5.
  static State typicalSize() { return State(Scalar(10), Scalar(5)); }
  /// A count to within 0.3 thousand.
  static Meas noiseStandardDeviation() { return Meas::Constant(Scalar(0.3)); }
};

/// The heated block (models/heated_block.hpp): 1800 s (three power cycles, nine slow time constants) at
/// h = 20 ms, both temperatures read every 0.1 s (noise 0.1 K), from room temperature.
///
/// Stability of the filters' I-TR-BDF2 at h: on ẋ = λx a step multiplies by R(z) = (1 + z/2)², z = hλ,
/// stable for real z in [−4, 0]. The fast eigenvalue, about −G_hb / C_h, is −10 /s at the truth (z = −0.2)
/// and −20 /s at the first guess G_hb = 40 W/K; h = 20 ms stays stable up to G_hb = 400 W/K, 20 times the
/// truth, well beyond any sigma point of the runs.
template <class Scalar = double>
struct HeatedBlockExperiment : GalleryExperiment<HeatedBlockExperiment<Scalar>, models::HeatedBlock<Scalar>> {
  /// The plant's vectors.
  using State = typename models::HeatedBlock<Scalar>::State;
  /// The measurement vector.
  using Meas = typename models::HeatedBlock<Scalar>::Meas;
  /// h (s).
  static constexpr Scalar stepSize = Scalar(0.02);
  /// 1800 s.
  static constexpr Scalar duration = Scalar(1800);
  /// A reading every 5 steps (0.1 s).
  static constexpr int measurementEvery = 5;
  /// The RMSE leaves out the first tenth of the run.
  static constexpr long rmseFromRow = 9000;  // t ≥ 180 s

  /// Both at the room's 20 °C.
  static State trueInitialState() { return State::Constant(Scalar(20)); }
  /// x̂₀ = x₀.
  static State initialState() { return State::Constant(Scalar(20)); }
  /// Room temperature to within 1 K.
  static State initialUncertainty() { return State::Constant(Scalar(1)); }
  /// Temperatures of order 40 °C.
  static State typicalSize() { return State::Constant(Scalar(40)); }
  /// Thermocouples of 0.1 K.
  static Meas noiseStandardDeviation() { return Meas::Constant(Scalar(0.1)); }
};

/// The drug infusion (models/michaelis_menten.hpp): 72 h at h = 0.01 h, the concentration read every
/// 0.1 h (noise 0.2 mg/L), from a patient free of the drug.
template <class Scalar = double>
struct DrugInfusionExperiment
    : GalleryExperiment<DrugInfusionExperiment<Scalar>, models::MichaelisMentenInfusion<Scalar>> {
  /// The plant's vectors.
  using State = typename models::MichaelisMentenInfusion<Scalar>::State;
  /// The measurement vector.
  using Meas = typename models::MichaelisMentenInfusion<Scalar>::Meas;
  /// h (hours).
  static constexpr Scalar stepSize = Scalar(0.01);
  /// Three days (hours).
  static constexpr Scalar duration = Scalar(72);
  /// A reading every 10 steps (6 minutes).
  static constexpr int measurementEvery = 10;
  /// The RMSE leaves out the first tenth of the run.
  static constexpr long rmseFromRow = 720;  // t ≥ 7.2 h

  /// Free of the drug: c₀ = 0.
  static State trueInitialState() { return State::Zero(); }
  /// x̂₀ = c₀.
  static State initialState() { return State::Zero(); }
  /// Known to be free of the drug, to within 0.1 mg/L.
  static State initialUncertainty() { return State::Constant(Scalar(0.1)); }
  /// Concentrations of order 10 mg/L.
  static State typicalSize() { return State::Constant(Scalar(10)); }
  /// An assay of 0.2 mg/L.
  static Meas noiseStandardDeviation() { return Meas::Constant(Scalar(0.2)); }
};

}  // namespace mjukf::gallery
