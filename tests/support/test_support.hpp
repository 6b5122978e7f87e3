#pragma once

// Models, steppers and helpers shared by the core tests.

#include <random>
#include <type_traits>

#include <Eigen/Core>

#include "mjukf/covariance_form.hpp"
#include "mjukf/dual_ukf.hpp"
#include "mjukf/filter_settings.hpp"
#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/models/flexible_joint.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"
#include "random_matrix.hpp"

namespace mjukf::testing {

/// ẋ = A x + B u(t), y = C x: a damped, coupled linear system with u(t) = sin t. The parameter vector
/// is empty; MeasDim < 3 observes the state partially.
template <int MeasDim_>
struct LinearModel {
  using Scalar = double;
  static constexpr int StateDim = 3, ParamDim = 0, MeasDim = MeasDim_, InputDim = 1;
  using State = Eigen::Matrix<double, StateDim, 1>;
  using Param = Eigen::Matrix<double, ParamDim, 1>;
  using Meas = Eigen::Matrix<double, MeasDim, 1>;
  using Input = Eigen::Matrix<double, InputDim, 1>;

  Eigen::Matrix3d A = (Eigen::Matrix3d() << -0.5, 1.0, 0.0,  //
                       -1.0, -0.2, 0.3,                      //
                       0.2, 0.0, -0.8)
                          .finished();
  Eigen::Vector3d B = Eigen::Vector3d(0.0, 1.0, 0.5);
  Eigen::Matrix<double, MeasDim, StateDim> C = Eigen::Matrix<double, MeasDim, StateDim>::Identity();

  Input input(double t) const { return Input::Constant(std::sin(t)); }
  State derivative(double, const State& x, const Input& u, const Param&) const { return A * x + B * u(0); }
  Meas measurement(const State& x, const Param&) const { return C * x; }
};

/// A stepper that counts its steps (one step = one model propagation of a point), through a pointer
/// so the count survives the copy a filter keeps.
template <class Inner>
struct CountingStepper {
  using Scalar = typename Inner::Scalar;
  static constexpr int order = Inner::order;
  static constexpr int evaluationsPerStep = Inner::evaluationsPerStep;
  Inner inner;
  long* steps = nullptr;

  template <class F, class State>
  State step(F&& f, Scalar t, const State& x, Scalar h) const {
    ++*steps;
    return inner.step(f, t, x, h);
  }
};

/// A symmetric N × N matrix, A + Aᵀ of a standard normal A: indefinite, in general.
template <int N>
Eigen::Matrix<double, N, N> randomSymmetric(std::mt19937_64& rng) {
  const auto a = randomNormal<Eigen::Matrix<double, N, N>>(rng);
  return a + a.transpose();
}

/// A random symmetric positive definite matrix with correlations, condition number moderate.
template <int N>
Eigen::Matrix<double, N, N> randomCovariance(std::mt19937_64& rng, double scale = 1.0) {
  const auto factor = randomNormal<Eigen::Matrix<double, N, N>>(rng);
  return scale * (factor * factor.transpose() + 0.1 * Eigen::Matrix<double, N, N>::Identity());
}

}  // namespace mjukf::testing

namespace mjukf::testing {

/// Explicit Euler, x + h f(t, x): one evaluation of f per step, so a model's derivative count is the
/// number of propagations of a point, and a component with zero derivative stays bit for bit unchanged.
template <class Scalar_ = double>
struct Euler {
  using Scalar = Scalar_;
  [[maybe_unused]] static constexpr int order = 1, evaluationsPerStep = 1;  // the stepper convention
  template <class F, class State>
  State step(F&& f, Scalar t, const State& x, Scalar h) const {
    return x + h * f(t, x);
  }
};

/// The flexible-joint robot discretised by explicit Euler, as a discrete-time model:
/// x_k = x_{k−1} + dt f(t, x_{k−1}, u(t), θ), with FlexibleJoint's measurement and input signal. Under
/// any filter it computes what the continuous robot under Euler does, with the same operations.
template <class Scalar_ = double>
struct DiscreteRobot {
  using Continuous = models::FlexibleJoint<Scalar_>;
  using Scalar = Scalar_;
  static constexpr int StateDim = 4, ParamDim = 2, MeasDim = 4, InputDim = 1;
  using State = typename Continuous::State;
  using Param = typename Continuous::Param;
  using Meas = typename Continuous::Meas;
  using Input = typename Continuous::Input;
  Continuous robot;
  Input input(Scalar t) const { return robot.input(t); }
  State transition(Scalar t, Scalar dt, const State& x, const Input& u, const Param& theta) const {
    return x + dt * robot.derivative(t, x, u, theta);
  }
  Meas measurement(const State& x, const Param& theta) const { return robot.measurement(x, theta); }
};

/// Filter template F (Ukf, JointUkf, ModifiedJointUkf, DualUkf, or one of them as SquareRoot<F>::Filter)
/// given model and stepper: which of the four it is, whatever its sigma-point set and covariance form.
enum class Family { Ukf, Joint, ModifiedJoint, Dual };
template <class T>
struct FamilyOf;
template <class M, class I, class P, class F>
struct FamilyOf<Ukf<M, I, P, F>> : std::integral_constant<Family, Family::Ukf> {};
template <class M, class I, class P, class F>
struct FamilyOf<JointUkf<M, I, P, F>> : std::integral_constant<Family, Family::Joint> {};
template <class M, class I, class P, class F>
struct FamilyOf<ModifiedJointUkf<M, I, P, F>> : std::integral_constant<Family, Family::ModifiedJoint> {};
template <class M, class I, class P, class F>
struct FamilyOf<DualUkf<M, I, P, F>> : std::integral_constant<Family, Family::Dual> {};
/// The family of filter template F (the type F<Model, int> is named, never instantiated).
template <template <class...> class F, class Model>
inline constexpr Family familyOf = FamilyOf<F<Model, int>>::value;

/// Filter template F in the square-root covariance form (covariance_form.hpp), with the default
/// sigma-point set: `SquareRoot<Ukf>::Filter<Model, Integrator>`, a template of (model, stepper) like
/// the filters themselves, for the typed suites.
template <template <class...> class F>
struct SquareRoot {
  template <class Model, class Integrator = DefaultIntegrator<Model>>
  using Filter = F<Model, Integrator, MerweScaled, SquareRootCovariance>;
};

/// The preset of the paper's `Experiment` for filter template F (the UKF's, JUKF's, MJUKF's or the dual
/// filter's, in either covariance form). Settings depend only on the sizes, so it serves any `Model`
/// of the experiment's shape.
template <template <class...> class F, class Experiment, class Model = typename Experiment::Model>
auto presetSettings() {
  using E = typename Experiment::Model;
  if constexpr (familyOf<F, E> == Family::Ukf)
    return Experiment::ukf();
  else if constexpr (familyOf<F, E> == Family::Joint)
    return Experiment::jointUkf();
  else if constexpr (familyOf<F, E> == Family::ModifiedJoint)
    return Experiment::modifiedJointUkf();
  else
    return Experiment::dualUkf();
}

/// The three filters on one experiment of the paper, built with its settings, so typed tests can
/// sweep filter × plant.
template <template <class...> class Filter, class Experiment>
struct PaperFilter {
  using Model = typename Experiment::Model;
  using Type = Filter<Model, ITrBdf2<typename Model::Scalar>>;
  static Type make() {
    constexpr bool knownParameters = familyOf<Filter, Model> == Family::Ukf;
    return Type(Model(), Experiment::initialState(),
                knownParameters ? Model::trueParameters() : Experiment::initialParameters(),
                presetSettings<Filter, Experiment>());
  }
};

}  // namespace mjukf::testing
