#pragma once

/// \file
/// SUNDIALS CVODE (variable-order, variable-step BDF) behind the library's stepper interface, as a
/// reference solution for tests and as a stepper for stiff models.
///
/// Needs SUNDIALS 6.x (Debian 12's `libsundials-dev` 6.4): link `SUNDIALS::cvode`,
/// `SUNDIALS::nvecserial`, `SUNDIALS::sunmatrixdense` and `SUNDIALS::sunlinsoldense`. Nothing else
/// in mjukf includes this header, so the core library needs only Eigen.
///
/// Unlike the other steppers this one allocates (SUNDIALS builds its context, vectors, dense matrix
/// and linear solver on the heap for every call): use it for references, for offline simulation and
/// for stiff models, not on an allocation-free filter hot path.

#include <cmath>
#include <cstdlib>
#include <exception>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include <Eigen/Core>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

namespace mjukf {

/// A SUNDIALS call failed; `flag()` is its return code (negative CVODE codes, see `cvode.h`).
class CvodeError : public std::runtime_error {
 public:
  /// An error with the CVODE return flag.
  CvodeError(const std::string& what, int flag) : std::runtime_error(what), flag_(flag) {}
  /// The CVODE return flag.
  int flag() const { return flag_; }

 private:
  int flag_;
};

/// Settings of a CVODE integration. CVODE controls the local error per internal step to
/// `relativeTolerance · |xᵢ| + absoluteTolerance`; the global error over a long horizon can be a few
/// orders of magnitude larger (docs/integrators.md measures it).
struct CvodeSettings {
  /// CVODE's relative tolerance.
  double relativeTolerance = 1e-10;
  /// CVODE's absolute tolerance.
  double absoluteTolerance = 1e-12;
  long maxSteps = 1000000;  ///< Internal steps allowed per output interval.
  double maxStep = 0;       ///< Largest internal step; 0 leaves it unlimited.
  int maxOrder = 5;         ///< Largest BDF order, 1 … 5.
};

/// Counters of one integration.
struct CvodeStats {
  long steps = 0;        ///< Internal steps.
  long evaluations = 0;  ///< Evaluations of f by CVODE (without its difference-quotient Jacobian).
};

/// \cond INTERNAL
namespace detail::cvode {

struct ContextDeleter {
  void operator()(SUNContext ctx) const { SUNContext_Free(&ctx); }
};
struct VectorDeleter {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
struct MatrixDeleter {
  void operator()(SUNMatrix m) const { SUNMatDestroy(m); }
};
struct SolverDeleter {
  void operator()(SUNLinearSolver s) const { SUNLinSolFree(s); }
};
struct MemoryDeleter {
  void operator()(void* mem) const { CVodeFree(&mem); }
};

inline void check(int flag, const char* call, const std::string& message = std::string()) {
  if (flag < 0) {
    // CVodeGetReturnFlagName returns a malloc'ed string the caller frees.
    const std::unique_ptr<char, decltype(&std::free)> name(CVodeGetReturnFlagName(flag), &std::free);
    std::string what = std::string("mjukf::Cvode: ") + call + " failed with " + (name ? name.get() : "?") + " (" +
                       std::to_string(flag) + ")";
    if (!message.empty()) what += ": " + message;
    throw CvodeError(what, flag);
  }
}

template <class T>
T* require(T* object, const char* call) {
  if (object == nullptr) throw CvodeError(std::string("mjukf::Cvode: ") + call + " returned null", CV_MEM_NULL);
  return object;
}

// The right-hand side and what it threw, passed to CVODE as user data. Exceptions must not cross
// CVODE's C frames: they are stored, CVODE is told the failure is unrecoverable, and the session
// rethrows.
template <class F, class State>
struct RhsData {
  F* f;
  std::exception_ptr thrown;
  std::string lastMessage;
};

// One CVODE integration from (t0, x0): owns every SUNDIALS object, frees them in reverse order.
template <class F, class State>
class Session {
 public:
  static constexpr int n = State::RowsAtCompileTime;
  using Scalar = typename State::Scalar;

  Session(F& f, double t0, const State& x0, const CvodeSettings& settings) : data_{&f, nullptr, {}} {
    SUNContext raw = nullptr;
    check(SUNContext_Create(nullptr, &raw), "SUNContext_Create");
    context_.reset(raw);
    y_.reset(require(N_VNew_Serial(n, context_.get()), "N_VNew_Serial"));
    Eigen::Map<Eigen::Matrix<sunrealtype, n, 1>>(N_VGetArrayPointer(y_.get())) = x0.template cast<sunrealtype>();
    matrix_.reset(require(SUNDenseMatrix(n, n, context_.get()), "SUNDenseMatrix"));
    solver_.reset(require(SUNLinSol_Dense(y_.get(), matrix_.get(), context_.get()), "SUNLinSol_Dense"));
    memory_.reset(require(CVodeCreate(CV_BDF, context_.get()), "CVodeCreate"));
    void* mem = memory_.get();
    check(CVodeSetErrHandlerFn(mem, &Session::errorHandler, &data_), "CVodeSetErrHandlerFn");
    check(CVodeInit(mem, &Session::rhs, t0, y_.get()), "CVodeInit");
    check(CVodeSStolerances(mem, settings.relativeTolerance, settings.absoluteTolerance), "CVodeSStolerances");
    check(CVodeSetUserData(mem, &data_), "CVodeSetUserData");
    check(CVodeSetLinearSolver(mem, solver_.get(), matrix_.get()), "CVodeSetLinearSolver");
    check(CVodeSetMaxNumSteps(mem, settings.maxSteps), "CVodeSetMaxNumSteps");
    check(CVodeSetMaxOrd(mem, settings.maxOrder), "CVodeSetMaxOrd");
    if (settings.maxStep > 0) check(CVodeSetMaxStep(mem, settings.maxStep), "CVodeSetMaxStep");
  }

  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // The solution at tout (CV_NORMAL: CVODE may step past tout and interpolates back).
  State advance(double tout) {
    double reached = 0;
    const int flag = CVode(memory_.get(), tout, y_.get(), &reached, CV_NORMAL);
    if (data_.thrown) std::rethrow_exception(data_.thrown);
    check(flag, "CVode", data_.lastMessage);
    return Eigen::Map<const Eigen::Matrix<sunrealtype, n, 1>>(N_VGetArrayPointer(y_.get())).template cast<Scalar>();
  }

  CvodeStats stats() const {
    CvodeStats s;
    check(CVodeGetNumSteps(memory_.get(), &s.steps), "CVodeGetNumSteps");
    check(CVodeGetNumRhsEvals(memory_.get(), &s.evaluations), "CVodeGetNumRhsEvals");
    return s;
  }

 private:
  static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* userData) {
    auto* data = static_cast<RhsData<F, State>*>(userData);
    try {
      const State x = Eigen::Map<const Eigen::Matrix<sunrealtype, n, 1>>(N_VGetArrayPointer(y)).template cast<Scalar>();
      const State dx = (*data->f)(static_cast<Scalar>(t), x);
      Eigen::Map<Eigen::Matrix<sunrealtype, n, 1>>(N_VGetArrayPointer(ydot)) = dx.template cast<sunrealtype>();
      return dx.allFinite() ? 0 : 1;  // recoverable: CVODE retries with a smaller step
    } catch (...) {
      data->thrown = std::current_exception();
      return -1;
    }
  }

  // Keeps CVODE from printing to stderr; the message goes into the exception instead.
  static void errorHandler(int /*code*/, const char* module, const char* function, char* msg, void* userData) {
    auto* data = static_cast<RhsData<F, State>*>(userData);
    data->lastMessage = std::string(module) + "::" + function + ": " + msg;
  }

  RhsData<F, State> data_;
  // Declaration order = construction order; destruction runs in reverse, memory before context.
  std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextDeleter> context_;
  std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter> y_;
  std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixDeleter> matrix_;
  std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, SolverDeleter> solver_;
  std::unique_ptr<void, MemoryDeleter> memory_;
};

}  // namespace detail::cvode
/// \endcond

/// `f(t, x) = model.derivative(t, x, model.input(t), θ)`: a model with its own input signal, as the
/// filters integrate it (detail/unscented_engine.hpp). The model is held by reference.
template <class Model>
auto modelRhs(const Model& model, const typename Model::Param& theta) {
  return [&model, theta](typename Model::Scalar t, const typename Model::State& x) ->
         typename Model::State { return model.derivative(t, x, model.input(t), theta); };
}

/// CVODE (BDF, Newton with a dense difference-quotient Jacobian) with the stepper interface:
/// `step(f, t, x, h)` integrates ẋ = f(t, x) over [t, t + h] to the settings' tolerances. Also
/// `integrate` over an interval and `integrateGrid`, which samples one solution on a uniform grid.
///
/// Every call builds and frees its own SUNDIALS objects (RAII), so the object is copyable and
/// const-callable like the other steppers, and allocates. Errors of `integrate` and `integrateGrid`
/// throw `CvodeError` (and an exception thrown by f is rethrown); `step` returns NaN instead, see
/// there; nothing is ignored. CVODE works in double: a float State is converted
/// on the way in and out, so tolerances below ~1e-6 mean nothing for float models.
template <class Scalar_ = double>
class Cvode {
 public:
  /// The floating-point type.
  using Scalar = Scalar_;
  /// Adaptive: BDF of order 1 … 5 with error control; `order` is the largest order it uses.
  static constexpr int order = 5;
  /// Not fixed: adaptive. `integrateGrid` reports the count.
  static constexpr int evaluationsPerStep = -1;

  /// A stepper with the given tolerances.
  explicit Cvode(const CvodeSettings& settings = CvodeSettings()) : settings_(settings) {
    if (!(settings.relativeTolerance >= 0) || !(settings.absoluteTolerance >= 0) ||
        !(settings.relativeTolerance + settings.absoluteTolerance > 0))
      throw std::invalid_argument("mjukf::Cvode: setting 'tolerances' must be non-negative, not both zero");
    if (settings.maxSteps < 1) throw std::invalid_argument("mjukf::Cvode: setting 'maxSteps' must be positive");
    if (settings.maxOrder < 1 || settings.maxOrder > 5)
      throw std::invalid_argument("mjukf::Cvode: setting 'maxOrder' must lie in 1 … 5");
  }

  /// The tolerances.
  const CvodeSettings& settings() const { return settings_; }

  /// x(t + h) from x(t) = x. As a filter's stepper it must report failure the way the filters
  /// understand: when CVODE fails (too much work, error test failures, a non-finite f), it returns a
  /// state of NaN, which the filter refuses with Status::NonFiniteResult, leaving its estimate intact.
  /// An exception thrown by f itself still propagates. `integrate` throws CvodeError instead.
  template <class F, class State>
  State step(F&& f, Scalar t, const State& x, Scalar h) const {
    try {
      return integrate(std::forward<F>(f), t, x, t + h);
    } catch (const CvodeError&) {
      return State::Constant(std::numeric_limits<Scalar>::quiet_NaN());
    }
  }

  /// x(t1) from x(t0) = x0.
  template <class F, class State>
  State integrate(F&& f, Scalar t0, const State& x0, Scalar t1) const {
    checkState<State>();
    detail::cvode::Session<std::remove_reference_t<F>, State> session(f, double(t0), x0, settings_);
    return session.advance(double(t1));
  }

  /// One solution from x(t0) = x0 sampled at t_k = t0 + k h, k = 0 … steps: calls
  /// `observer(k, t_k, x_k)` for each (CV_NORMAL output to every grid time, so CVODE keeps its own
  /// step sizes and interpolates). Returns CVODE's counters.
  template <class F, class State, class Observer>
  CvodeStats integrateGrid(F&& f, Scalar t0, const State& x0, Scalar h, long steps, Observer&& observer) const {
    checkState<State>();
    detail::cvode::Session<std::remove_reference_t<F>, State> session(f, double(t0), x0, settings_);
    observer(0L, t0, x0);
    for (long k = 1; k <= steps; ++k) {
      const double tk = double(t0) + double(k) * double(h);
      observer(k, Scalar(tk), session.advance(tk));
    }
    return session.stats();
  }

 private:
  template <class State>
  static constexpr void checkState() {
    static_assert(State::RowsAtCompileTime != Eigen::Dynamic && State::ColsAtCompileTime == 1,
                  "mjukf::Cvode needs a fixed-size column vector");
  }

  CvodeSettings settings_;
};

}  // namespace mjukf
