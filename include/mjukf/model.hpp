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
///   // y = g(x, θ), or, for a measurement that depends on the input, y = g(x, u, θ) (give exactly one):
///   Meas measurement(const State& x, const Param& theta) const;
///   // Meas measurement(const State& x, const Input& u, const Param& theta) const;
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
///
/// `stepModel` below says what one step of a model is (an integrator step, or the transition): the
/// filters, `simulate` (simulation.hpp) and the programs take every step of a model through it.

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
struct HasInputSignal<T, std::void_t<decltype(std::declval<const T&>().input(std::declval<typename T::Scalar>()))>>
    : std::true_type {};

// Detection of each model function by its call alone; its return type is checked separately
// (ReturnsVector), so that a function returning the wrong type is named in checkModel's message
// instead of being taken for a missing one.
template <class T, class = void>
struct HasDerivative : std::false_type {};
template <class T>
struct HasDerivative<T, std::void_t<decltype(std::declval<const T&>().derivative(
                            std::declval<typename T::Scalar>(), std::declval<const typename T::State&>(),
                            std::declval<const typename T::Input&>(), std::declval<const typename T::Param&>()))>>
    : std::true_type {
  using Result = decltype(std::declval<const T&>().derivative(
      std::declval<typename T::Scalar>(), std::declval<const typename T::State&>(),
      std::declval<const typename T::Input&>(), std::declval<const typename T::Param&>()));
};

template <class T, class = void>
struct HasTransition : std::false_type {};
template <class T>
struct HasTransition<T, std::void_t<decltype(std::declval<const T&>().transition(
                            std::declval<typename T::Scalar>(), std::declval<typename T::Scalar>(),
                            std::declval<const typename T::State&>(), std::declval<const typename T::Input&>(),
                            std::declval<const typename T::Param&>()))>> : std::true_type {
  using Result = decltype(std::declval<const T&>().transition(
      std::declval<typename T::Scalar>(), std::declval<typename T::Scalar>(), std::declval<const typename T::State&>(),
      std::declval<const typename T::Input&>(), std::declval<const typename T::Param&>()));
};

// y = g(x, θ)
template <class T, class = void>
struct HasMeasurement : std::false_type {};
template <class T>
struct HasMeasurement<T, std::void_t<decltype(std::declval<const T&>().measurement(
                             std::declval<const typename T::State&>(), std::declval<const typename T::Param&>()))>>
    : std::true_type {
  using Result = decltype(std::declval<const T&>().measurement(std::declval<const typename T::State&>(),
                                                               std::declval<const typename T::Param&>()));
};

// y = g(x, u, θ)
template <class T, class = void>
struct HasInputMeasurement : std::false_type {};
template <class T>
struct HasInputMeasurement<T, std::void_t<decltype(std::declval<const T&>().measurement(
                                  std::declval<const typename T::State&>(), std::declval<const typename T::Input&>(),
                                  std::declval<const typename T::Param&>()))>> : std::true_type {
  using Result = decltype(std::declval<const T&>().measurement(std::declval<const typename T::State&>(),
                                                               std::declval<const typename T::Input&>(),
                                                               std::declval<const typename T::Param&>()));
};

// True when `Result` (a model function's return type, references and const removed) is a column
// vector of `Rows` entries of `Scalar` with its size fixed at compile time: Eigen would convert a
// vector of another size and fail far from the model (YOU_MIXED_MATRICES_OF_DIFFERENT_SIZES).
template <class Result, class Scalar, int Rows, class = void>
struct ReturnsVector : std::false_type {};
template <class Result, class Scalar, int Rows>
struct ReturnsVector<Result, Scalar, Rows, std::void_t<typename std::decay_t<Result>::Scalar>>
    : std::bool_constant<std::is_same_v<typename std::decay_t<Result>::Scalar, Scalar>&& int(
                             std::decay_t<Result>::RowsAtCompileTime) ==
                         Rows&& int(std::decay_t<Result>::ColsAtCompileTime) == 1> {};

// The return type of a detected function, or void when it is absent (checked only where present).
template <class Has, class = void>
struct ResultOf {
  using type = void;
};
template <class Has>
struct ResultOf<Has, std::void_t<typename Has::Result>> {
  using type = typename Has::Result;
};

template <class Model, class Has, int Rows>
constexpr bool returnsVectorIfPresent() {
  if constexpr (Has::value)
    return ReturnsVector<typename ResultOf<Has>::type, typename Model::Scalar, Rows>::value;
  else
    return true;
}

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

/// True when the model's measurement depends on the input, `measurement(x, u, θ)`, rather than
/// `measurement(x, θ)`. A filter then passes, at a measurement update, the input in force at the
/// measurement time: the model's `input(t)` at the filter's time (the end of its last time update or
/// open-loop propagation), or the `u` given to `measurementUpdate(y, u)`.
template <class Model>
inline constexpr bool measurementTakesInput = detail::HasInputMeasurement<Model>::value;

/// The integrator of a filter over a discrete-time model: none. It only marks the slot.
template <class Scalar_>
struct NoIntegrator {
  /// The floating-point type.
  using Scalar = Scalar_;
};

/// The integrator a filter uses when none is named: the paper's I-TR-BDF2 (first order; see
/// docs/integrators.md for the others) for a continuous model, none for a discrete-time one.
template <class Model>
using DefaultIntegrator =
    std::conditional_t<isDiscreteTime<Model>, NoIntegrator<typename Model::Scalar>, ITrBdf2<typename Model::Scalar>>;

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
  static_assert(detail::HasMeasurement<Model>::value || detail::HasInputMeasurement<Model>::value,
                "Model needs `Meas measurement(const State&, const Param&) const` or, for a measurement that "
                "depends on the input, `Meas measurement(const State&, const Input&, const Param&) const`");
  static_assert(!(detail::HasMeasurement<Model>::value && detail::HasInputMeasurement<Model>::value),
                "Model has both `measurement(x, theta)` and `measurement(x, u, theta)`: give one, so that it is "
                "clear which input a filter passes");
  static_assert(detail::returnsVectorIfPresent<Model, detail::HasDerivative<Model>, Model::StateDim>(),
                "Model::derivative must return a column vector of StateDim entries of Scalar (Model::State)");
  static_assert(detail::returnsVectorIfPresent<Model, detail::HasTransition<Model>, Model::StateDim>(),
                "Model::transition must return a column vector of StateDim entries of Scalar (Model::State)");
  static_assert(detail::returnsVectorIfPresent<Model, detail::HasMeasurement<Model>, Model::MeasDim>() &&
                    detail::returnsVectorIfPresent<Model, detail::HasInputMeasurement<Model>, Model::MeasDim>(),
                "Model::measurement must return a column vector of MeasDim entries of Scalar (Model::Meas)");
  return true;
}

/// y = g(x, u, θ) or g(x, θ), whichever the model gives: the one place the filters, `simulate` and the
/// programs evaluate a measurement. `u` is ignored when the measurement does not depend on the input.
template <class Model>
typename Model::Meas measureModel(const Model& model, const typename Model::State& x, const typename Model::Input& u,
                                  const typename Model::Param& theta) {
  if constexpr (measurementTakesInput<Model>) {
    return model.measurement(x, u, theta);
  } else {
    static_cast<void>(u);
    return model.measurement(x, theta);
  }
}

/// \cond INTERNAL
namespace detail {

// An input source as stepModel takes it, made callable: a held value (any expression convertible to
// Model::Input is evaluated once), or the caller's callable t -> Input as it is.
template <class Model, class Inputs>
auto inputSource(const Inputs& inputs) {
  using Input = typename Model::Input;
  using Scalar = typename Model::Scalar;
  if constexpr (std::is_convertible_v<const Inputs&, Input>) {
    return [u = Input(inputs)](Scalar) -> const Input& { return u; };
  } else {
    static_assert(std::is_invocable_r_v<Input, const Inputs&, Scalar>,
                  "the input must be a Model::Input (held over the step) or a callable Scalar t -> Model::Input");
    return [&inputs](Scalar t) -> decltype(auto) { return inputs(t); };
  }
}

}  // namespace detail
/// \endcond

/// One integrator step of size h of `model` from the state x at time t under the parameters θ:
/// x⁺ = Φ_h(x; t, θ), with ẋ = f(t, x, u(t), θ) = model.derivative(t, x, u, θ); for a discrete-time
/// model (model.hpp), x⁺ = model.transition(t, h, x, u(t), θ), and the integrator is not used.
///
/// `inputs` gives u: either a `Model::Input` (or an expression convertible to it), held constant over
/// the step (zero-order hold, as `timeUpdate(t, h, u)` does), or a callable `Scalar t -> Model::Input`,
/// evaluated at every stage time the integrator asks for (as `timeUpdate(t, h)` does with the model's
/// own `input(t)`).
///
/// `simulate`, and the simulations of the tests, examples and benchmarks, take every step of a model
/// through this function: it is the one place that says what one step of the plant is.
template <class Model, class Integrator, class Inputs>
typename Model::State stepModel(const Model& model, const Integrator& integrator, typename Model::Scalar t,
                                typename Model::Scalar h, const typename Model::State& x, const Inputs& inputs,
                                const typename Model::Param& theta) {
  static_assert(checkModel<Model>());
  using Scalar = typename Model::Scalar;
  using State = typename Model::State;
  const auto input = detail::inputSource<Model>(inputs);
  if constexpr (isDiscreteTime<Model>) {
    static_cast<void>(integrator);
    return model.transition(t, h, x, input(t), theta);  // the input at the start of the step
  } else {
    const auto rhs = [&](Scalar time, const State& z) -> State {
      return model.derivative(time, z, input(time), theta);
    };
    return integrator.step(rhs, t, x, h);
  }
}

}  // namespace mjukf
