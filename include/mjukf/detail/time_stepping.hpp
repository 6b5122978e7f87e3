#pragma once

// The public time-update and open-loop overloads every filter offers, written once. A filter derives
// from TimeStepping<Filter, Model> and provides timeUpdateWith(input, t, h, steps) and
// propagateMeanWith(input, t, h, steps); this base supplies the input: the model's own signal u(t), or
// a value the caller holds constant over the step.

#include "mjukf/detail/finite.hpp"
#include "mjukf/detail/propagation.hpp"
#include "mjukf/model.hpp"
#include "mjukf/status.hpp"

namespace mjukf::detail {

template <class Derived, class Model>
class TimeStepping {
 public:
  using Scalar = typename Model::Scalar;
  using Input = typename Model::Input;

  /// Unscented time update (algorithms.md §2) from t over `steps` integrator steps of size h, with the
  /// model's input signal u(t) evaluated at every stage time (once per distinct stage time, shared by
  /// all sigma points). The sigma points are drawn once at t and propagated through all steps; Q is
  /// added once.
  template <class M = Model>
  Status timeUpdate(Scalar t, Scalar h, int steps = 1) {
    static_assert(hasInputSignal<M>, "this model has no input(t): pass the input, timeUpdate(t, h, u)");
    return self().timeUpdateWith(SharedSignalInput<Model>(self().model()), t, h, steps);
  }

  /// Unscented time update with the input u held constant over the steps (zero-order hold).
  Status timeUpdate(Scalar t, Scalar h, const Input& u, int steps = 1) {
    if (!allFinite(u)) return Status::NonFiniteInput;
    return self().timeUpdateWith(HeldInput<Model>{u}, t, h, steps);
  }

  /// Open-loop propagation of the mean alone (algorithms.md §7), covariance unchanged: the paper's
  /// schedule between measurements. Input from the model's signal u(t).
  template <class M = Model>
  Status propagateMean(Scalar t, Scalar h, int steps = 1) {
    static_assert(hasInputSignal<M>, "this model has no input(t): pass the input, propagateMean(t, h, u)");
    return self().propagateMeanWith(SignalInput<Model>{self().model()}, t, h, steps);
  }

  /// Open-loop propagation of the mean alone with the input u held constant over the steps.
  Status propagateMean(Scalar t, Scalar h, const Input& u, int steps = 1) {
    if (!allFinite(u)) return Status::NonFiniteInput;
    return self().propagateMeanWith(HeldInput<Model>{u}, t, h, steps);
  }

 protected:
  TimeStepping() = default;

 private:
  Derived& self() { return static_cast<Derived&>(*this); }
};

}  // namespace mjukf::detail
