// Prints the accuracy and cost tables of docs/integrators.md, in Markdown, from the same code the
// SundialsCrossCheck tests assert on (cross_check.hpp).
//
//   cmake --build <build> --target integrator_table && <build>/tests/integrators/integrator_table

#include <cstdio>
#include <string>
#include <vector>

#include "cross_check.hpp"

namespace {

using namespace mjukf;
using namespace mjukf::crosscheck;

std::string sci(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.2e", v);
  return buffer;
}
std::string fixed(double v, int digits) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, v);
  return buffer;
}
std::string ms(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g ms", v);
  return buffer;
}

void table(Scenario s, const std::vector<double>& steps, const Reference& ref, const char* refName, double refError) {
  std::printf("\n#### %s, against CVODE %s (its own max error ≤ %s)\n\n", name(s), refName, sci(refError).c_str());
  std::printf("| stepper | order | f / step |");
  for (double h : steps) std::printf(" h = %s |", ms(h).c_str());
  for (std::size_t i = 0; i + 1 < steps.size(); ++i) std::printf(" p %g→%g |", steps[i], steps[i + 1]);
  std::printf("\n|---|---|---|");
  for (std::size_t i = 0; i < 2 * steps.size() - 1; ++i) std::printf("---|");
  std::printf("\n");
  for (const Row& r : rows(s, steps, ref, refError)) {
    std::printf("| %s | %d | %s |", r.stepper.c_str(), r.declaredOrder, fixed(r.evaluations, 2).c_str());
    for (double e : r.errors) std::printf(" %s |", r.finite ? sci(e).c_str() : "diverged");
    for (std::size_t i = 0; i < r.orders.size(); ++i)
      std::printf(" %s%s |", fixed(r.orders[i], 2).c_str(), r.resolved[i] ? "" : " (floor)");
    std::printf("\n");
  }
}

template <class Stepper>
void costRow(const char* label, const Stepper& stepper, long steps) {
  std::printf("| %s | %s | %s |\n", label,
              fixed(nanosecondsPerStep(stepper, Scenario::Robot, 1e-3, steps, 11), 1).c_str(),
              fixed(nanosecondsPerStep(stepper, Scenario::TankFromTen, 1e-3, steps, 11), 1).c_str());
}

}  // namespace

int main() {
  const Scenario scenarios[] = {Scenario::Robot, Scenario::TankFromTen, Scenario::TankFromRest};
  std::vector<References> refs;
  for (Scenario s : scenarios) refs.push_back(references(s));

  std::printf(
      "### References\n\n| scenario | CVODE internal steps (rtol 1e-10) | f evaluations | "
      "max error of rtol 1e-10 | max error of rtol 1e-13 (bound) |\n|---|---|---|---|---|\n");
  for (std::size_t i = 0; i < refs.size(); ++i)
    std::printf("| %s | %ld | %ld | %s | %s |\n", name(scenarios[i]), refs[i].standard.stats.steps,
                refs[i].standard.stats.evaluations, sci(refs[i].standardError).c_str(),
                sci(refs[i].tightError).c_str());

  std::printf("\n### The issue's steps against the issue's reference (rtol 1e-10, atol 1e-12)\n");
  for (std::size_t i = 0; i < refs.size(); ++i)
    table(scenarios[i], stepsMs(), refs[i].standard, "rtol 1e-10, atol 1e-12", refs[i].standardError);

  std::printf("\n### Asymptotic orders against the tight reference (rtol 1e-13, atol 1e-15)\n");
  for (std::size_t i = 0; i < refs.size(); ++i) {
    const Scenario s = scenarios[i];
    table(s, s == Scenario::TankFromRest ? stepsMs() : asymptoticStepsMs(s), refs[i].tight, "rtol 1e-13, atol 1e-15",
          refs[i].tightError);
  }

  std::printf(
      "\n### I-TR-BDF2's leading error\n\n"
      "C = max_t ‖E(t)‖∞ from E' = J E + ẍ/4, E(0) = 0; columns: measured max error / (C h), against the "
      "tight reference.\n\n");
  std::printf("| scenario | C | h = 4 ms | 2 ms | 1 ms | 0.5 ms |\n|---|---|---|---|---|---|\n");
  for (std::size_t i = 0; i < refs.size(); ++i) {
    const double c = iTrBdf2ErrorConstant(scenarios[i]);
    std::printf("| %s | %s |", name(scenarios[i]), sci(c).c_str());
    for (double h : stepsMs())
      std::printf(
          " %s |",
          fixed(run(ITrBdf2<double>(), scenarios[i], h * 1e-3, refs[i].tight).maxError / (c * h * 1e-3), 4).c_str());
    std::printf("\n");
  }

  std::printf("\n### Cost per step at h = 1 ms (median of 11 runs, ns per step)\n\n");
  std::printf("| stepper | robot | tank |\n|---|---|---|\n");
  costRow("I-TR-BDF2", ITrBdf2<double>(), 200000);
  costRow("explicit TR-BDF2", ExplicitTrBdf2<double>(), 200000);
  costRow("TR-BDF2 (implicit, finite-difference Jacobian)", TrBdf2<double>(), 200000);
  costRow("RK4", Rk4<double>(), 200000);
  costRow("CVODE as a stepper (rtol 1e-10, atol 1e-12)", Cvode<double>(), 2000);
  return 0;
}
