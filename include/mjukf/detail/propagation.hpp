#pragma once

// Integrating a model over whole integrator steps with a given parameter vector: the one operation
// every filter repeats for each sigma point and for the open-loop mean.

#include <cmath>

#include "mjukf/model.hpp"
#include "mjukf/simulation.hpp"
#include "mjukf/status.hpp"

// GCC and Clang: inline every call made in the function, recursively (what the compiler can see).
// The propagation of the points is the bulk of a step, and left to its own budget the compiler keeps
// the stepper, the model's derivative and Eigen's 4-vector assignments as separate calls there, which
// costs a third more than the same arithmetic inlined (bench/: step against floor). Not when
// optimising for size (-Os, firmware): there the calls are what the build asked for.
#if (defined(__GNUC__) || defined(__clang__)) && !defined(__OPTIMIZE_SIZE__)
#define MJUKF_FLATTEN __attribute__((flatten))
#else
#define MJUKF_FLATTEN
#endif

namespace mjukf::detail {

// The model's own input signal u(t), evaluated at every stage time: for the open-loop mean, one point.
template <class Model>
struct SignalInput {
  const Model& model;
  typename Model::Input operator()(typename Model::Scalar t) const { return model.input(t); }
};

// The model's own input signal u(t) for a time update, which propagates all its sigma points over the
// same stage times: the last few distinct times and their values are kept, so u(t) is evaluated once
// per stage time rather than once per point and stage (the values are the same, since input(t) is a
// function of t alone; see model.hpp). Lives for one call; no allocation.
template <class Model>
class SharedSignalInput {
 public:
  using Scalar = typename Model::Scalar;
  using Input = typename Model::Input;

  explicit SharedSignalInput(const Model& model) : model_(model) {}

  const Input& operator()(Scalar t) const {
    // The points ask for the same times in the same order: try the slot after the last one first.
    if (hint_ < size_ && times_[hint_] == t) return hit(hint_);
    for (int i = 0; i < size_; ++i)
      if (times_[i] == t) return hit(i);
    // A miss replaces the oldest entry, so more distinct times than slots only cost the search.
    const int slot = next_;
    next_ = (next_ + 1) % Capacity;
    if (size_ < Capacity) ++size_;
    times_[slot] = t;
    values_[slot] = model_.input(t);
    return hit(slot);
  }

 private:
  // Enough for the stage times of one step of any stepper here (I-TR-BDF2 and RK4 have 3).
  static constexpr int Capacity = 8;

  const Input& hit(int slot) const {
    hint_ = slot + 1 < size_ ? slot + 1 : 0;
    return values_[slot];
  }

  const Model& model_;
  mutable Scalar times_[Capacity];  // only the first size_ are set
  mutable Input values_[Capacity];
  mutable int size_ = 0;
  mutable int next_ = 0;
  mutable int hint_ = 0;
};

// An input held constant over the step (zero-order hold), for inputs known only as samples.
template <class Model>
struct HeldInput {
  const typename Model::Input& value;
  const typename Model::Input& operator()(typename Model::Scalar /*t*/) const { return value; }
};

template <class Scalar>
Status checkStep(Scalar t, Scalar h, int steps) {
  if (!std::isfinite(t) || !std::isfinite(h) || !(h > 0) || steps < 1) return Status::InvalidStepSize;
  return Status::Ok;
}

// x(t + steps h) from x(t) by `steps` steps of size h under parameters theta, each one stepModel
// (simulation.hpp): an integrator step of a continuous model, or the transition of a discrete-time one.
template <class Model, class Integrator, class InputSource, class StateExpr>
MJUKF_FLATTEN typename Model::State propagate(const Model& model, const Integrator& integrator, const InputSource& input,
                                const typename Model::Param& theta, typename Model::Scalar t,
                                typename Model::Scalar h, int steps, const StateExpr& x0) {
  using Scalar = typename Model::Scalar;
  typename Model::State x = x0;
  for (int k = 0; k < steps; ++k) x = stepModel(model, integrator, t + Scalar(k) * h, h, x, input, theta);
  return x;
}

}  // namespace mjukf::detail
