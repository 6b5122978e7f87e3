#pragma once

/// \file
/// The model concept every filter is generic over, checked at compile time.
///
/// A model is a plain struct:
///
/// \code
/// struct MyPlant {
///   using Scalar = double;
///   static constexpr int StateDim = 2, ParamDim = 1, MeasDim = 2, InputDim = 1;
///   using State = Eigen::Matrix<Scalar, StateDim, 1>;   // and Param, Meas, Input likewise
///   // ẋ = f(x, u, θ, t)
///   State derivative(Scalar t, const State& x, const Input& u, const Param& theta) const;
///   // y = g(x, θ)
///   Meas measurement(const State& x, const Param& theta) const;
///   // Optional: a known input signal u(t), evaluated at every stage time of the integrator. It must
///   // be a function of t alone: a time update evaluates it once per distinct stage time and gives
///   // the value to every sigma point.
///   Input input(Scalar t) const;
/// };
/// \endcode
///
/// A model **without input** has `InputDim = 0` and needs no `input(t)`: `derivative` still receives
/// the (empty) `Input`, and the filters' `timeUpdate(t, h)` and `propagateMean(t, h)` and `simulate`
/// take no input argument.
///
/// A **discrete-time** model (the paper's eq. 6, x_k = F(x_{k−1}, u_{k−1}, θ_{k−1})) provides, instead
/// of `derivative`, the next state over a step of length dt from time t, with the input at t:
///
/// \code
///   State transition(Scalar t, Scalar dt, const State& x, const Input& u, const Param& theta) const;
/// \endcode
///
/// A filter over such a model takes no integrator (its integrator slot defaults to `NoIntegrator`); a
/// time update over `steps` steps of h applies `transition` `steps` times, at t, t + h, ….
///
/// Physical constants are ordinary data members, so the same model can be built with other constants.

#include <type_traits>
#include <utility>

#include <Eigen/Core>

#include "mjukf/integrators/i_tr_bdf2.hpp"

namespace mjukf {

/// \cond INTERNAL
namespace detail {

template <class T, class = void>
struct HasInputSignal : std::false_type {};
template <class T>
struct HasInputSignal<T, std::void_t<decltype(std::declval<const T&>().input(
                             std::declval<typename T::Scalar>()))>> : std::true_type {};

template <class T, class = void>
struct HasDerivative : std::false_type {};
template <class T>
struct HasDerivative<T, std::void_t<decltype(std::declval<const T&>().derivative(
                            std::declval<typename T::Scalar>(), std::declval<const typename T::State&>(),
                            std::declval<const typename T::Input&>(),
                            std::declval<const typename T::Param&>()))>>
    : std::is_convertible<decltype(std::declval<const T&>().derivative(
                              std::declval<typename T::Scalar>(), std::declval<const typename T::State&>(),
                              std::declval<const typename T::Input&>(),
                              std::declval<const typename T::Param&>())),
                          typename T::State> {};

template <class T, class = void>
struct HasTransition : std::false_type {};
template <class T>
struct HasTransition<T, std::void_t<decltype(std::declval<const T&>().transition(
                            std::declval<typename T::Scalar>(), std::declval<typename T::Scalar>(),
                            std::declval<const typename T::State&>(), std::declval<const typename T::Input&>(),
                            std::declval<const typename T::Param&>()))>>
    : std::is_convertible<decltype(std::declval<const T&>().transition(
                              std::declval<typename T::Scalar>(), std::declval<typename T::Scalar>(),
                              std::declval<const typename T::State&>(), std::declval<const typename T::Input&>(),
                              std::declval<const typename T::Param&>())),
                          typename T::State> {};

template <class T, class = void>
struct HasMeasurement : std::false_type {};
template <class T>
struct HasMeasurement<T, std::void_t<decltype(std::declval<const T&>().measurement(
                             std::declval<const typename T::State&>(),
                             std::declval<const typename T::Param&>()))>>
    : std::is_convertible<decltype(std::declval<const T&>().measurement(
                              std::declval<const typename T::State&>(),
                              std::declval<const typename T::Param&>())),
                          typename T::Meas> {};

template <class Scalar, int Rows>
using Vector = Eigen::Matrix<Scalar, Rows, 1>;

}  // namespace detail
/// \endcond

/// True when `Model` provides `input(t)`, a known input signal; filters then offer time updates that
/// evaluate it at each stage time.
template <class Model>
inline constexpr bool hasInputSignal = detail::HasInputSignal<Model>::value;

/// True when a filter's `timeUpdate(t, h)` and `propagateMean(t, h)` need no input argument: the model
/// has its own signal `input(t)`, or no input at all (InputDim = 0, no `input(t)` needed).
template <class Model>
inline constexpr bool needsNoInputArgument = hasInputSignal<Model> || Model::InputDim == 0;

/// True when `Model` is given in discrete time, by `transition` (the next state) rather than
/// `derivative`.
template <class Model>
inline constexpr bool isDiscreteTime = detail::HasTransition<Model>::value;

/// The integrator of a filter over a discrete-time model: none. It only marks the slot.
template <class Scalar_>
struct NoIntegrator {
  /// The floating-point type.
  using Scalar = Scalar_;
};

/// The integrator a filter uses when none is named: the paper's I-TR-BDF2 (first order; see
/// docs/integrators.md for the others) for a continuous model, none for a discrete-time one.
template <class Model>
using DefaultIntegrator = std::conditional_t<isDiscreteTime<Model>, NoIntegrator<typename Model::Scalar>,
                                             ITrBdf2<typename Model::Scalar>>;

/// Checks the model concept at compile time; every filter calls it. `MinParamDim` is 1 for the joint
/// filters, which estimate parameters, and 0 for the plain UKF.
template <class Model, int MinParamDim = 0>
constexpr bool checkModel() {
  using Scalar = typename Model::Scalar;
  static_assert(std::is_floating_point_v<Scalar>, "Model::Scalar must be float, double or long double");
  static_assert(Model::StateDim > 0, "Model::StateDim must be positive");
  static_assert(Model::ParamDim >= MinParamDim, "Model::ParamDim is too small for this filter");
  static_assert(Model::MeasDim > 0, "Model::MeasDim must be positive");
  static_assert(Model::InputDim >= 0, "Model::InputDim must not be negative");
  static_assert(std::is_same_v<typename Model::State, detail::Vector<Scalar, Model::StateDim>>,
                "Model::State must be Eigen::Matrix<Scalar, StateDim, 1>");
  static_assert(std::is_same_v<typename Model::Param, detail::Vector<Scalar, Model::ParamDim>>,
                "Model::Param must be Eigen::Matrix<Scalar, ParamDim, 1>");
  static_assert(std::is_same_v<typename Model::Meas, detail::Vector<Scalar, Model::MeasDim>>,
                "Model::Meas must be Eigen::Matrix<Scalar, MeasDim, 1>");
  static_assert(std::is_same_v<typename Model::Input, detail::Vector<Scalar, Model::InputDim>>,
                "Model::Input must be Eigen::Matrix<Scalar, InputDim, 1>");
  static_assert(detail::HasDerivative<Model>::value || detail::HasTransition<Model>::value,
                "Model needs `State derivative(Scalar t, const State&, const Input&, const Param&) const` (continuous "
                "time) or `State transition(Scalar t, Scalar dt, const State&, const Input&, const Param&) const` "
                "(discrete time)");
  static_assert(!(detail::HasDerivative<Model>::value && detail::HasTransition<Model>::value),
                "Model has both `derivative` and `transition`: give one, so that it is clear whether the filter "
                "integrates it");
  static_assert(detail::HasMeasurement<Model>::value,
                "Model needs `Meas measurement(const State&, const Param&) const`");
  return true;
}

}  // namespace mjukf
