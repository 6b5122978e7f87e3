#pragma once

// The cross-check of the steppers against CVODE, shared by the tests (sundials_cross_check_test.cpp)
// and the program that prints the table of docs/integrators.md (integrator_table.cpp), so that the
// numbers in the doc are the ones the tests assert on.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "mjukf/integrators/explicit_tr_bdf2.hpp"
#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/integrators/tr_bdf2.hpp"
#include "mjukf/models/coupled_tank.hpp"
#include "mjukf/models/flexible_joint.hpp"
#include "mjukf/sundials/cvode.hpp"

namespace mjukf::crosscheck {

// Steps of the study, in ms; the reference is sampled on the finest grid.
inline const std::vector<double>& stepsMs() {
  static const std::vector<double> steps{4, 2, 1, 0.5};
  return steps;
}
constexpr double finestStep = 0.5e-3;

enum class Scenario { Robot, TankFromTen, TankFromRest };

inline const char* name(Scenario s) {
  switch (s) {
    case Scenario::Robot: return "robot, from rest, 20 s";
    case Scenario::TankFromTen: return "tank, from h1 = h2 = 10 cm, 200 s";
    case Scenario::TankFromRest: return "tank, from rest, 200 s";
  }
  return "?";
}

inline double horizon(Scenario s) { return s == Scenario::Robot ? 20.0 : 200.0; }

// Runs `body(f, x0)` with the scenario's right-hand side (true parameters, the model's own input
// evaluated at every stage time) and initial state.
template <class Body>
auto withScenario(Scenario s, Body&& body) {
  if (s == Scenario::Robot) {
    static const models::FlexibleJoint<double> robot;
    const auto f = modelRhs(robot, models::FlexibleJoint<double>::trueParameters());
    return body(f, models::FlexibleJoint<double>::State::Zero().eval());
  }
  static const models::CoupledTank<double> tank;
  const auto f = modelRhs(tank, models::CoupledTank<double>::trueParameters());
  const double start = s == Scenario::TankFromTen ? 10.0 : 0.0;
  return body(f, models::CoupledTank<double>::State::Constant(start).eval());
}

// The solution as flat rows of the finest grid, t_k = k · 0.5 ms.
struct Reference {
  int dim = 0;
  std::vector<double> values;  // row-major, (steps + 1) × dim
  CvodeStats stats;
  double at(long k, int i) const { return values[std::size_t(k) * std::size_t(dim) + std::size_t(i)]; }
  long rows() const { return long(values.size()) / dim; }
};

inline Reference reference(Scenario s, double rtol, double atol) {
  return withScenario(s, [&](const auto& f, const auto& x0) {
    Reference ref;
    ref.dim = int(x0.size());
    const long steps = std::lround(horizon(s) / finestStep);
    ref.values.reserve(std::size_t(steps + 1) * std::size_t(ref.dim));
    CvodeSettings settings;
    settings.relativeTolerance = rtol;
    settings.absoluteTolerance = atol;
    ref.stats = Cvode<double>(settings).integrateGrid(f, 0.0, x0, finestStep, steps, [&](long, double, const auto& x) {
      for (int i = 0; i < x.size(); ++i) ref.values.push_back(x(i));
    });
    return ref;
  });
}

// max over the grid of ‖a − b‖∞.
inline double maxDifference(const Reference& a, const Reference& b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.values.size(); ++i) worst = std::max(worst, std::abs(a.values[i] - b.values[i]));
  return worst;
}

// The references of one scenario and what each is worth. CVODE bounds local errors only, so each
// reference's global error is measured against a tighter one:
//   standard: rtol 1e-10, atol 1e-12 (the tolerances); its error `standardError` is its
//             distance from `tight`.
//   tight:    rtol 1e-13, atol 1e-15; `tightError` is its distance from a third solution at rtol
//             1e-12, atol 1e-14. That is an over-estimate: CVODE's global error falls with its
//             tolerance (here by ~50× from 1e-10 to 1e-12), so the distance 1e-12 ↔ 1e-13 is mostly
//             the 1e-12 solution's own error.
struct References {
  Reference standard, tight;
  double standardError = 0, tightError = 0;
};

inline References references(Scenario s) {
  References r;
  r.standard = reference(s, 1e-10, 1e-12);
  r.tight = reference(s, 1e-13, 1e-15);
  r.standardError = maxDifference(r.standard, r.tight);
  r.tightError = maxDifference(reference(s, 1e-12, 1e-14), r.tight);
  return r;
}

// An observed order log2(e(h)/e(h/2)) is only trusted when e(h/2) is at least this many times the
// reference's own error: a reference error δ moves the estimate by up to ~2.9 δ/e(h/2), ≤ 0.1 here,
// leaving the rest of the ±0.3 band to the higher-order terms.
constexpr double resolution = 30;

struct Run {
  double maxError = 0;     // max over the horizon of ‖x_k − x_ref(t_k)‖∞
  double evaluations = 0;  // mean evaluations of f per step
  bool finite = true;
};

// `stepper` at step h over the scenario's horizon, compared with `ref` at every step.
template <class Stepper>
Run run(const Stepper& stepper, Scenario s, double h, const Reference& ref) {
  return withScenario(s, [&](const auto& f, const auto& x0) {
    long count = 0;
    const auto counted = [&](double t, const auto& x) {
      ++count;
      return f(t, x);
    };
    const long stride = std::lround(h / finestStep);
    const long steps = std::lround(horizon(s) / h);
    if (std::abs(double(stride) * finestStep - h) > 1e-12 || std::abs(double(steps) * h - horizon(s)) > 1e-9)
      throw std::invalid_argument("crosscheck::run: h must divide the horizon and be a multiple of 0.5 ms");
    Run result;
    auto x = x0;
    for (long k = 1; k <= steps; ++k) {
      x = stepper.step(counted, double(k - 1) * h, x, h);
      for (int i = 0; i < x.size(); ++i)
        result.maxError = std::max(result.maxError, std::abs(x(i) - ref.at(k * stride, i)));
      if (!x.allFinite()) {
        result.finite = false;
        break;
      }
    }
    result.evaluations = double(count) / double(steps);
    return result;
  });
}

// Observed order from two errors at h and h/2.
inline double observedOrder(double coarse, double fine) { return std::log2(coarse / fine); }

// One stepper on one scenario at a sequence of halving steps.
struct Row {
  std::string stepper;
  int declaredOrder = 0;
  double evaluations = 0;  // largest mean over the steps
  bool finite = true;
  std::vector<double> errors;
  std::vector<double> orders;  // orders[i] from errors[i], errors[i + 1]
  std::vector<bool> resolved;  // errors[i + 1] ≥ resolution × the reference's error
};

template <class Stepper>
Row row(const char* label, const Stepper& stepper, Scenario s, const std::vector<double>& stepsInMs,
        const Reference& ref, double referenceError) {
  Row r;
  r.stepper = label;
  r.declaredOrder = Stepper::order;
  for (double ms : stepsInMs) {
    const Run run1 = run(stepper, s, ms * 1e-3, ref);
    r.errors.push_back(run1.maxError);
    r.finite = r.finite && run1.finite;
    r.evaluations = std::max(r.evaluations, run1.evaluations);
  }
  for (std::size_t i = 0; i + 1 < r.errors.size(); ++i) {
    r.orders.push_back(observedOrder(r.errors[i], r.errors[i + 1]));
    r.resolved.push_back(r.errors[i + 1] >= resolution * referenceError);
  }
  return r;
}

// The four steppers of the study, in the order of the tables.
inline std::vector<Row> rows(Scenario s, const std::vector<double>& stepsInMs, const Reference& ref,
                             double referenceError) {
  return {row("I-TR-BDF2 (γ = 0.5)", ITrBdf2<double>(), s, stepsInMs, ref, referenceError),
          row("explicit TR-BDF2 (γ = 0.5)", ExplicitTrBdf2<double>(), s, stepsInMs, ref, referenceError),
          row("TR-BDF2 (implicit, γ = 2 − √2)", TrBdf2<double>(), s, stepsInMs, ref, referenceError),
          row("RK4", Rk4<double>(), s, stepsInMs, ref, referenceError)};
}

// Steps of the asymptotic-order study, where every stepper's error stands well above the tight
// reference's: the robot's linearisation at rest has |λ| ≤ 11.5 /s (h|λ| ≤ 0.37 at 32 ms); the tank's
// Jacobian has |λ| = c/(2A√hᵢ) ≤ 0.051 /s for levels ≥ 10 cm (h|λ| ≤ 0.08 at 1.6 s).
inline std::vector<double> asymptoticStepsMs(Scenario s) {
  if (s == Scenario::Robot) return {32, 16, 8, 4};
  return {1600, 800, 400, 200};
}

// The leading global error of I-TR-BDF2. Written as a Runge–Kutta method its weights give
// Σ bᵢcᵢ = 1/4 for every γ, so one step is short by (h²/4)·ẍ + O(h³). The global error
// e(t) = x(t) − x_k then is h·E(t) + O(h²) with E' = J(t) E + ẍ/4, E(0) = 0 (the standard
// error-propagation equation; Hairer, Nørsett & Wanner I, §II.8). This integrates [x; E] with RK4 at
// the finest step, J E and ẍ = J f + ∂f/∂t by central differences, and returns max_t ‖E(t)‖∞.
inline double iTrBdf2ErrorConstant(Scenario s) {
  return withScenario(s, [&](const auto& f, const auto& x0) {
    using State = std::decay_t<decltype(x0)>;
    constexpr int n = State::RowsAtCompileTime;
    using Augmented = Eigen::Matrix<double, 2 * n, 1>;
    const auto g = [&](double t, const Augmented& z) -> Augmented {
      const State x = z.template head<n>();
      const State e = z.template tail<n>();
      const State fx = f(t, x);
      const double ex = 1e-6 * std::max(1.0, x.cwiseAbs().maxCoeff());
      const double en = e.cwiseAbs().maxCoeff();
      State je = State::Zero();
      if (en > 0) {
        const double eps = ex / en;
        je = (f(t, State(x + eps * e)) - f(t, State(x - eps * e))) / (2 * eps);
      }
      const double d = 1e-6;
      const State xddot = (f(t + d, State(x + d * fx)) - f(t - d, State(x - d * fx))) / (2 * d);
      Augmented out;
      out << fx, je + 0.25 * xddot;
      return out;
    };
    Augmented z = Augmented::Zero();
    z.template head<n>() = x0;
    const long steps = std::lround(horizon(s) / finestStep);
    double worst = 0;
    const Rk4<double> rk4;
    for (long k = 0; k < steps; ++k) {
      z = rk4.step(g, double(k) * finestStep, z, finestStep);
      worst = std::max(worst, z.template tail<n>().cwiseAbs().maxCoeff());
    }
    return worst;
  });
}

// Median wall time of one step, in ns, over `repeats` runs of `steps` steps from the scenario's start.
template <class Stepper>
double nanosecondsPerStep(const Stepper& stepper, Scenario s, double h, long steps, int repeats) {
  return withScenario(s, [&](const auto& f, const auto& x0) {
    std::vector<double> samples;
    volatile double sink = 0;
    for (int r = 0; r < repeats; ++r) {
      auto x = x0;
      const auto begin = std::chrono::steady_clock::now();
      for (long k = 0; k < steps; ++k) x = stepper.step(f, double(k) * h, x, h);
      const auto end = std::chrono::steady_clock::now();
      sink = sink + x(0);
      samples.push_back(std::chrono::duration<double, std::nano>(end - begin).count() / double(steps));
    }
    std::sort(samples.begin(), samples.end());
    return samples[samples.size() / 2];
  });
}

}  // namespace mjukf::crosscheck
