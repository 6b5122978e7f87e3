#pragma once

// The automatic MJUKF's test for a change of the parameters (docs/algorithms.md §5.4; not in the paper).
// Its gain from the joint covariance (§5.3) takes θ as constant, so P_θ only shrinks and a θ that has
// changed would be followed ever more slowly; this test finds such a change in the innovations and
// says how large it is, and the filter widens P_θ by it.

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "mjukf/detail/linear_algebra.hpp"

namespace mjukf::detail {

/// ln Γ(p / 2) for p ≥ 1, from Γ(k) = (k − 1)! and Γ(k + ½) = √π (1/2)(3/2)…(k − ½): std::lgamma may
/// write the global signgam, which a filter built on two threads must not.
template <class Scalar>
Scalar logGammaOfHalf(int p) {
  Scalar sum = p % 2 == 0 ? Scalar(0) : Scalar(0.5) * std::log(Scalar(3.14159265358979323846));
  for (int k = p % 2 == 0 ? 1 : 0; 2 * k + (p % 2) < p; ++k) sum += std::log(Scalar(k) + Scalar(p % 2) / Scalar(2));
  return sum;
}

/// The largest false-alarm probability `chiSquaredUpperQuantile` serves (its tail form needs x ≫ p).
inline constexpr double kLargestFalseAlarm = 1e-3;

/// χ²ₚ's upper quantile at probability α ≤ 1e-3 (the x with P(χ²ₚ > x) = α): the fixed point of the
/// tail's asymptotic form Q(s, y) ≈ y^(s−1) e^(−y) (1 + (s − 1) / y) / Γ(s), s = p / 2, y = x / 2, exact
/// for p = 2 and 4 and off by the series' next term, (s − 1)(s − 2) / y², elsewhere (tested against the
/// closed forms for p = 1, 2, 4). The iteration converges because y > s there.
template <class Scalar>
Scalar chiSquaredUpperQuantile(int p, Scalar alpha) {
  const Scalar s = Scalar(p) / Scalar(2);
  const Scalar logTail = -std::log(alpha) - logGammaOfHalf<Scalar>(p);
  Scalar y = -std::log(alpha) + s;
  for (int i = 0; i < 100; ++i) {
    const Scalar next = logTail + (s - Scalar(1)) * std::log(y) + std::log1p((s - Scalar(1)) / y);
    if (std::abs(next - y) <= Scalar(4) * std::numeric_limits<Scalar>::epsilon() * y) return Scalar(2) * next;
    y = next;
  }
  return Scalar(2) * y;
}

/// A score test over a fading window. With gⱼ = ψⱼᵀ Sⱼ⁻¹ νⱼ (ψ = ∂ŷ/∂θ̂, S the innovations' covariance the
/// joint covariance predicts, ν = y − ŷ, the state's innovation) and λ the memory's forgetting factor, it keeps
///   s = Σ λ^(k−j) gⱼ,   V = Σ λ^(2(k−j)) gⱼ gⱼᵀ,   I = Σ λ^(k−j) ψⱼᵀ Sⱼ⁻¹ ψⱼ,
/// and tests z = sᵀ V⁻¹ s against χ²ₚ's 1 − α quantile. With θ constant the innovations are white and of
/// mean zero, so s has covariance V and z is about χ²ₚ; a change δ of θ adds about I δ to s, and its least
/// squares estimate is δ̂ = I⁻¹ s. V is the sample covariance of the gⱼ, not I: an R set smaller or larger
/// than the sensor's noise (the paper's plants set it 50 to 10⁶ times too small) scales s and V alike and
/// neither makes the test fire nor blinds it; δ̂ does not depend on that scale either. The window
/// restarts after a detection and while the filter eases its steps in (the state still settling, whose
/// error the innovations then carry). Candidates and commit as everywhere; fixed sizes, no allocation.
template <class Scalar, int M, int P>
class ParameterChangeDetector {
 public:
  using Param = Eigen::Matrix<Scalar, P, 1>;
  using ParamMatrix = Eigen::Matrix<Scalar, P, P>;
  using MeasSensitivity = Eigen::Matrix<Scalar, M, P>;
  using Meas = Eigen::Matrix<Scalar, M, 1>;

  /// An empty window; a false-alarm probability α per test (0: never a detection).
  void start(Scalar falseAlarm) {
    threshold_ =
        falseAlarm > Scalar(0) ? chiSquaredUpperQuantile(P, falseAlarm) : std::numeric_limits<Scalar>::infinity();
    clearWindow(committed_);
    committed_.changes = 0;
    committed_.statistic = Scalar(0);
    candidate_ = committed_;
  }

  /// One measurement update, into the candidate: `whitenedSensitivity` = L⁻¹ ψ and `whitenedInnovation`
  /// = L⁻¹ ν with S = L Lᵀ, `forgetting` λ, `armed` false while the steps are eased in (the window stays
  /// empty), and a test once the window holds at least `minimumCount` updates and at least the threshold's
  /// worth: z ≤ the number of updates in the window (Cauchy–Schwarz), so a shorter one cannot pass. True
  /// on a detection, with δ̂ in `change`.
  bool update(const MeasSensitivity& whitenedSensitivity, const Meas& whitenedInnovation, Scalar forgetting,
              Scalar minimumCount, bool armed, Param& change) {
    Window& w = candidate_;
    w = committed_;
    if (!armed) {
      clearWindow(w);
      return false;
    }
    const Param g = whitenedSensitivity.transpose() * whitenedInnovation;
    w.score = forgetting * w.score + g;
    w.scoreCovariance = forgetting * forgetting * w.scoreCovariance;
    w.scoreCovariance.noalias() += g * g.transpose();
    w.information = forgetting * w.information;
    w.information.noalias() += whitenedSensitivity.transpose() * whitenedSensitivity;
    ++w.count;
    if (Scalar(w.count) < std::max(minimumCount, threshold_) || !allFinite(w.score)) return false;
    Param solved;
    if (!solveSemidefinite(w.scoreCovariance, w.score, solved)) return false;
    w.statistic = w.score.dot(solved);  // z = sᵀ V⁻¹ s
    if (!(w.statistic > threshold_)) return false;
    if (!solveSemidefinite(w.information, w.score, change)) return false;  // δ̂ = I⁻¹ s
    if (!allFinite(change)) return false;
    clearWindow(w);
    ++w.changes;
    return true;
  }
  void commit() { committed_ = candidate_; }
  /// Drops the candidate (a measurement update that will not be committed, or a detection withdrawn).
  void discard() { candidate_ = committed_; }
  /// An empty window, keeping the count of changes (a new pass over a record).
  void restartWindow() {
    clearWindow(committed_);
    candidate_ = committed_;
  }

  /// The changes detected since the start.
  long changes() const { return committed_.changes; }
  /// z of the last test (0 before one).
  Scalar statistic() const { return committed_.statistic; }
  /// The threshold z is tested against, χ²ₚ's 1 − α quantile (infinite with α = 0).
  Scalar threshold() const { return threshold_; }

 private:
  // x = (A + δ I)⁻¹ b for a positive semi-definite A, δ = p ε tr A: a parameter the measurements do not
  // move has gⱼ = 0, a zero row in V and I and a zero entry in s, and so drops out of the test (its x is
  // 0) instead of blocking the factorisation. False when A is zero or not finite.
  static bool solveSemidefinite(const ParamMatrix& a, const Param& b, Param& x) {
    const Scalar trace = a.trace();
    if (!(trace > Scalar(0)) || !std::isfinite(trace)) return false;
    ParamMatrix regularised = a;
    regularised.diagonal().array() += Scalar(P) * std::numeric_limits<Scalar>::epsilon() * trace;
    ParamMatrix factor;
    if (!choleskyLower(regularised, factor)) return false;
    x = b;
    solveLowerInPlace(factor, x);
    solveUpperInPlace(factor, x);
    return true;
  }

  struct Window {
    Param score = Param::Zero();                        // s
    ParamMatrix scoreCovariance = ParamMatrix::Zero();  // V
    ParamMatrix information = ParamMatrix::Zero();      // I
    long count = 0;                                     // updates in the window
    long changes = 0;                                   // detections since the start
    Scalar statistic = 0;                               // z of the last test
  };
  static void clearWindow(Window& w) {
    w.score.setZero();
    w.scoreCovariance.setZero();
    w.information.setZero();
    w.count = 0;
  }

  Scalar threshold_ = std::numeric_limits<Scalar>::infinity();
  Window committed_, candidate_;
};

}  // namespace mjukf::detail
