#pragma once

/// \file
/// The classic implicit TR-BDF2 (Bank et al. 1985; Hosea & Shampine 1996), L-stable, second order.

#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include <Eigen/Core>
#include <Eigen/LU>

#include "mjukf/detail/validation.hpp"
#include "mjukf/result.hpp"
#include "mjukf/settings_error.hpp"

namespace mjukf {

/// \cond INTERNAL
namespace detail {

template <class F, class Scalar, class State, class = void>
struct HasJacobian : std::false_type {};
template <class F, class Scalar, class State>
struct HasJacobian<
    F, Scalar, State,
    std::void_t<decltype(std::declval<const F&>().jacobian(std::declval<Scalar>(), std::declval<const State&>()))>>
    : std::true_type {};

}  // namespace detail
/// \endcond

/// A right-hand side `f(t, x)` bundled with its Jacobian `jacobian(t, x)` = ∂f/∂x, which TrBdf2 then
/// uses instead of finite differences. Build one with `withJacobian(f, jacobian)`.
template <class F, class J>
struct RhsWithJacobian {
  /// The right-hand side f(t, x).
  F rhs;
  /// Its Jacobian ∂f/∂x(t, x).
  J jacobianOf;
  /// f(t, x).
  template <class Scalar, class State>
  auto operator()(Scalar t, const State& x) const {
    return rhs(t, x);
  }
  /// ∂f/∂x at (t, x).
  template <class Scalar, class State>
  auto jacobian(Scalar t, const State& x) const {
    return jacobianOf(t, x);
  }
};

/// Bundles `f(t, x)` with `jacobian(t, x)` (returning the n×n matrix ∂f/∂x) for TrBdf2.
template <class F, class J>
RhsWithJacobian<std::decay_t<F>, std::decay_t<J>> withJacobian(F&& f, J&& jacobian) {
  return {std::forward<F>(f), std::forward<J>(jacobian)};
}

/// Settings of TrBdf2's Newton iterations.
template <class Scalar>
struct TrBdf2Settings {
  /// A stage has converged when every Newton correction satisfies |Δᵢ| ≤ tolerance · (1 + |zᵢ|).
  Scalar tolerance = Scalar(100) * std::numeric_limits<Scalar>::epsilon();
  /// Newton iterations allowed per stage and per Jacobian; after a failure the Jacobian is
  /// re-evaluated at the current iterate and the stage gets the same number again, once.
  int maxIterations = 10;
};

/// What one TrBdf2 step did, from `tryStep`.
struct TrBdf2Report {
  bool converged = false;  ///< Both stages met the Newton tolerance.
  int evaluations = 0;     ///< Evaluations of f, including the finite-difference Jacobian's.
  int jacobians = 0;       ///< Jacobians evaluated (finite differences or the callable's own).
  int iterations = 0;      ///< Newton iterations over both stages.
};

/// One step of the classic TR-BDF2 with γ = 2 − √2: a trapezoidal stage to t + γh and a BDF2 stage
/// to t + h, both implicit and solved by Newton's method,
///
///     x_γ = x + (γh/2) [f(t, x) + f(t + γh, x_γ)]                                trapezoidal stage
///     x(t + h) ≈ x_γ / (γ(2−γ)) − (1−γ)²/(γ(2−γ)) x + (1−γ)/(2−γ) h f(t + h, x(t + h))   BDF2 stage
///
/// With γ = 2 − √2 both stages have the coefficient d = γ/2 = (1−γ)/(2−γ) in front of h f, so both
/// Newton iterations use the same matrix I − d h J, factored once per step (simplified Newton). The
/// method is second order and L-stable, for stiff models; for the library's two plants the explicit
/// steppers are cheaper at the same accuracy (docs/integrators.md).
///
/// J = ∂f/∂x comes from `f.jacobian(t, x)` when the callable has one (see `withJacobian`), otherwise
/// from forward differences at (t, x), n extra evaluations of f. Fixed-size vectors and matrices
/// throughout: a step allocates nothing.
///
/// Failure policy: a stage that has not met the tolerance after `maxIterations` corrections (or whose
/// corrections grow, or whose Newton matrix is singular) gets a fresh Jacobian at the current iterate
/// and one more round. If that fails too, `step` returns a state whose every component is NaN, never
/// a half-converged one: the filters then refuse the update with `Status::NonFiniteResult` and keep
/// their estimate. `tryStep` returns the same state together with a report saying what happened.
template <class Scalar_>
class TrBdf2 {
 public:
  /// The floating-point type.
  using Scalar = Scalar_;
  /// The order of convergence.
  static constexpr int order = 2;
  /// Not fixed: 1 + n (finite-difference Jacobian; 1 with a provided Jacobian) + one per Newton
  /// iteration of each stage. `tryStep` reports the count; docs/integrators.md has measured means.
  static constexpr int evaluationsPerStep = -1;

  /// The default settings, which are valid.
  TrBdf2() : settings_() {}
#if MJUKF_EXCEPTIONS
  /// Throws std::invalid_argument naming the setting when one is invalid (`validate`). Without
  /// exceptions, use `create`.
  explicit TrBdf2(const TrBdf2Settings<Scalar>& settings)
      : TrBdf2(detail::throwIfInvalid(validate(settings)), settings) {}
#endif
  /// The stepper, or the SettingsError naming the first invalid setting.
  static Result<TrBdf2> create(const TrBdf2Settings<Scalar>& settings) {
    return detail::resultOf<TrBdf2>(validate(settings), [&] { return TrBdf2(detail::Validated{}, settings); });
  }
  /// The first invalid setting (owner, setting, reason), or no error.
  static SettingsError validate(const TrBdf2Settings<Scalar>& settings) {
    if (!(settings.tolerance > 0) || !std::isfinite(settings.tolerance))
      return detail::invalid("mjukf::TrBdf2", "tolerance", "must be finite and positive");
    if (settings.maxIterations < 1) return detail::invalid("mjukf::TrBdf2", "maxIterations", "must be at least 1");
    return {};
  }

  /// γ = 2 − √2, the L-stable choice with equal stage coefficients.
  static Scalar gamma() { return Scalar(2) - std::sqrt(Scalar(2)); }
  /// The Newton settings.
  const TrBdf2Settings<Scalar>& settings() const { return settings_; }

  /// The state at t + h, or all NaN when Newton failed (see the class comment).
  template <class F, class State>
  State step(F&& f, Scalar t, const State& x, Scalar h) const {
    TrBdf2Report report;
    return tryStep(f, t, x, h, report);
  }

  /// As `step`, and says in `report` whether Newton converged and what it cost.
  template <class F, class State>
  State tryStep(F&& f, Scalar t, const State& x, Scalar h, TrBdf2Report& report) const {
    constexpr int n = State::RowsAtCompileTime;
    static_assert(n != Eigen::Dynamic && State::ColsAtCompileTime == 1, "TrBdf2 needs a fixed-size column vector");
    using Matrix = Eigen::Matrix<Scalar, n, n>;
    report = TrBdf2Report();

    const Scalar g = gamma();
    const Scalar d = g / Scalar(2);  // = (1−γ)/(2−γ)
    const Scalar dh = d * h;
    const Scalar bdf2 = g * (Scalar(2) - g);

    const State fk = f(t, x);
    ++report.evaluations;
    Matrix jac;
    jacobian(f, t, x, fk, jac, report);
    Eigen::PartialPivLU<Matrix> lu;
    bool factored = factor(jac, dh, lu);

    // Stage 1: G(z) = z − d h f(t + γh, z) − (x + d h f_k) = 0, started from the Euler predictor.
    const State rhs1 = x + dh * fk;
    State xGamma = x + (g * h) * fk;
    if (!solveStage(f, t + g * h, rhs1, dh, xGamma, jac, lu, factored, report)) return failed<State>(report);

    // Stage 2: G(z) = z − d h f(t + h, z) − (x_γ − (1−γ)² x) / (γ(2−γ)) = 0, started from the line
    // through x and x_γ extrapolated to t + h.
    const State rhs2 = (xGamma - (Scalar(1) - g) * (Scalar(1) - g) * x) / bdf2;
    State xNext = x + (xGamma - x) / g;
    if (!solveStage(f, t + h, rhs2, dh, xNext, jac, lu, factored, report)) return failed<State>(report);
    report.converged = true;
    return xNext;
  }

 private:
  TrBdf2(detail::Validated, const TrBdf2Settings<Scalar>& settings) : settings_(settings) {}
  template <class State>
  static State failed(TrBdf2Report& report) {
    report.converged = false;
    return State::Constant(std::numeric_limits<Scalar>::quiet_NaN());
  }

  template <class Matrix>
  static bool factor(const Matrix& jac, Scalar dh, Eigen::PartialPivLU<Matrix>& lu) {
    if (!jac.allFinite()) return false;
    lu.compute(Matrix::Identity() - dh * jac);
    // PartialPivLU does not report singularity; a zero or non-finite pivot shows in the determinant.
    const Scalar det = lu.determinant();
    return std::isfinite(det) && det != Scalar(0);
  }

  // ∂f/∂x at (t, x): the callable's own when it has one, else forward differences with steps
  // √ε·max(|xⱼ|, 1), which balance truncation against rounding.
  template <class F, class State, class Matrix>
  static void jacobian(F& f, Scalar t, const State& x, const State& fx, Matrix& jac, TrBdf2Report& report) {
    ++report.jacobians;
    if constexpr (detail::HasJacobian<std::decay_t<F>, Scalar, State>::value) {
      jac = f.jacobian(t, x);
    } else {
      const Scalar root = std::sqrt(std::numeric_limits<Scalar>::epsilon());
      State shifted = x;
      for (int j = 0; j < State::RowsAtCompileTime; ++j) {
        const Scalar delta = root * std::max(std::abs(x(j)), Scalar(1));
        shifted(j) = x(j) + delta;
        const Scalar actual = shifted(j) - x(j);  // the step the floating-point grid really took
        jac.col(j) = (f(t, shifted) - fx) / actual;
        shifted(j) = x(j);
        ++report.evaluations;
      }
    }
  }

  // Simplified Newton on z − d h f(τ, z) = rhs. Returns false only after a second round with a fresh
  // Jacobian also failed.
  template <class F, class State, class Matrix>
  bool solveStage(F& f, Scalar tau, const State& rhs, Scalar dh, State& z, Matrix& jac, Eigen::PartialPivLU<Matrix>& lu,
                  bool& factored, TrBdf2Report& report) const {
    for (int round = 0; round < 2; ++round) {
      if (round == 1) {  // refresh the Jacobian at the current iterate (or the start, if z went bad)
        if (!z.allFinite()) return false;
        const State fz = f(tau, z);
        ++report.evaluations;
        jacobian(f, tau, z, fz, jac, report);
        factored = factor(jac, dh, lu);
      }
      if (!factored) continue;
      Scalar previous = std::numeric_limits<Scalar>::infinity();
      for (int it = 0; it < settings_.maxIterations; ++it) {
        const State residual = z - dh * f(tau, z) - rhs;
        ++report.evaluations;
        ++report.iterations;
        const State delta = lu.solve(residual);
        if (!delta.allFinite()) break;
        z -= delta;
        const Scalar size = (delta.array().abs() / (Scalar(1) + z.array().abs())).maxCoeff();
        if (size <= settings_.tolerance) return z.allFinite();
        if (it > 0 && size >= previous) break;  // not contracting: this Jacobian will not do
        previous = size;
      }
    }
    return false;
  }

  TrBdf2Settings<Scalar> settings_;
};

}  // namespace mjukf
