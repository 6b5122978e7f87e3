// The firmware example (docs/embedded.md): the flexible-joint robot's filters in float on a Cortex-M4F,
// on measurements the program makes itself, with the paper's schedule, and the figures of the target.
//
// For each filter built in (EMBEDDED_FILTERS, a bit per filter, the four in the full and in the
// square-root covariance form; 0 builds the plant simulation alone, the baseline the flash figures
// subtract), with the features EMBEDDED_WITHOUT leaves out (features.hpp; none by default), the program
//   1. asks the factory for a filter with a broken R and checks that it names the setting (the
//      exception-free validation path, on the target);
//   2. builds the filter with the robot's settings (examples/support/paper/experiments.hpp) by create();
//   3. simulates the robot in float with the true parameters (0.15, 0.21) at h = 1 ms, measures every
//      state with Gaussian noise of σ = 0.03 from a fixed-seed xorshift generator, and runs the paper's
//      schedule (a time and measurement update every 5 rows, open-loop propagation between;
//      paper::runSchedule of examples/support/paper/) over 20 s;
//   4. checks that the parameter estimates end near the truth;
//   5. prints the estimate every second as the bits of each float, and the filter's figures: sizeof,
//      SysTick ticks of its measurement steps and open-loop steps, the stack high-water mark of a
//      measurement step.
// It ends with the heap calls the wrapped malloc counted, and exits 0 when every run went through.
// The host build of the same source prints the same lines, and the same run in double (lines "d"):
// scripts/embedded.sh compares the target's float run with the host's and takes its tolerance from the
// double run (docs/embedded.md). No stdio, no heap: a line is built in a fixed buffer.

#include <cstdint>
#include <cstring>

#include "mjukf/features.hpp"
#include "mjukf/simulation.hpp"
#include "paper/experiments.hpp"
#include "paper/schedule.hpp"
#include "platform.hpp"

#ifndef EMBEDDED_FILTERS
// 1 UKF, 2 JUKF, 4 MJUKF, 8 dual UKF; 16, 32, 64, 128 the same four in the square-root covariance form
#define EMBEDDED_FILTERS 255
#endif
#ifndef EMBEDDED_WITHOUT
// What every filter of the image is compiled without: 1 the health monitor, 2 the MJUKF's automatic
// modes, 3 both; 0 nothing (the default).
#define EMBEDDED_WITHOUT 0
#endif

namespace {

// The filters' last template argument (features.hpp): what a firmware that uses neither the health
// monitor nor the automatic modes writes is the first.
#if EMBEDDED_WITHOUT == 3
using Features = mjukf::Without<mjukf::feature::HealthMonitor, mjukf::feature::AutomaticModes>;
#elif EMBEDDED_WITHOUT == 2
using Features = mjukf::Without<mjukf::feature::AutomaticModes>;
#elif EMBEDDED_WITHOUT == 1
using Features = mjukf::Without<mjukf::feature::HealthMonitor>;
#else
using Features = mjukf::AllFeatures;
#endif

constexpr long kRows = 20001;       // 20 s at h = 1 ms, row 0 the initial estimate
constexpr long kPrintEvery = 1000;  // one estimate line a second
constexpr std::uint32_t kStackPaintDepth = 8192;

// ---- Output without stdio ------------------------------------------------------------------------

class Line {
 public:
  Line& text(const char* s) {
    while (*s && used_ + 2 < sizeof(buffer_)) buffer_[used_++] = *s++;
    return *this;
  }
  Line& number(std::uint64_t value) {
    char digits[21];
    int n = 0;
    do {
      digits[n++] = static_cast<char>('0' + value % 10);
      value /= 10;
    } while (value);
    while (n) put(digits[--n]);
    return *this;
  }
  // The bits of a float (8 hex digits) or a double (16), exact and the same on every machine.
  template <class Scalar>
  Line& bits(Scalar value) {
    using Bits = std::conditional_t<sizeof(Scalar) == 4, std::uint32_t, std::uint64_t>;
    Bits b;
    std::memcpy(&b, &value, sizeof b);
    put(' ');
    for (int shift = 8 * static_cast<int>(sizeof b) - 4; shift >= 0; shift -= 4)
      put("0123456789abcdef"[(b >> shift) & 0xF]);
    return *this;
  }
  void write() {
    buffer_[used_++] = '\n';
    buffer_[used_] = '\0';
    embedded::writeText(buffer_);
  }

 private:
  void put(char c) {
    if (used_ + 2 < sizeof(buffer_)) buffer_[used_++] = c;
  }
  char buffer_[200] = {};
  std::size_t used_ = 0;
};

template <class Scalar>
constexpr const char* scalarName() {
  return sizeof(Scalar) == 4 ? "f" : "d";
}

// ---- The plant and its measurements --------------------------------------------------------------

// xorshift32 (Marsaglia 2003): deterministic and the same on every machine.
class Xorshift32 {
 public:
  std::uint32_t next() {
    state_ ^= state_ << 13;
    state_ ^= state_ >> 17;
    state_ ^= state_ << 5;
    return state_;
  }
  // Approximately N(0, 1): the sum of 12 uniforms on [0, 1) minus 6 (Irwin–Hall), no libm. Each uniform
  // is a 24-bit integer times 2^-24, exact in float.
  template <class Scalar>
  Scalar gaussian() {
    Scalar sum = 0;
    for (int i = 0; i < 12; ++i) sum += Scalar(next() >> 8) * Scalar(1.0f / 16777216.0f);
    return sum - Scalar(6);
  }

 private:
  std::uint32_t state_ = 2463534242u;
};

// The robot simulated row by row as the schedule asks for measurements (rows only increase).
template <class Scalar>
class Plant {
 public:
  using Experiment = mjukf::paper::FlexibleJointExperiment<Scalar>;
  using Model = typename Experiment::Model;

  const typename Model::Meas& measurementAt(long row) {
    for (; row_ < row; ++row_) x_ = mjukf::stepModel(model_, integrator_, Scalar(row_) * h_, h_, x_, theta_);
    for (int j = 0; j < Model::MeasDim; ++j) y_(j) = x_(j) + kNoise * noise_.template gaussian<Scalar>();
    return y_;
  }

 private:
  static constexpr Scalar kNoise = Scalar(0.03);  // σ of every channel; R = 1e-3 in the filters
  Model model_;
  mjukf::DefaultIntegrator<Model> integrator_;
  typename Model::Param theta_ = Model::trueParameters();
  typename Model::State x_ = Experiment::initialState();
  typename Model::Meas y_;
  Scalar h_ = Experiment::stepSize;
  long row_ = 0;
  Xorshift32 noise_;
};

// ---- One filter's run ----------------------------------------------------------------------------

struct Figures {
  std::uint64_t measurementTicks = 0, openLoopTicks = 0;
  long measurementSteps = 0, openLoopSteps = 0;
  std::uint32_t stackHighWater = 0;
};

// What runSchedule drives: the filter, with the clock and the stack paint around each step. A
// measurement step is the time update and the measurement update (the plant's simulation between them,
// in measurementAt, is not counted).
template <class Filter>
struct Measured {
  using Scalar = typename Filter::Scalar;
  Filter& filter;
  Figures& figures;

  template <class Step>
  mjukf::Status measure(std::uint64_t& total, Step&& step) {
    embedded::paintStack(kStackPaintDepth);
    const std::uint32_t start = embedded::ticks();
    const mjukf::Status status = step();
    total += (embedded::ticks() - start) & ((1u << embedded::tickBits) - 1u);
    const std::uint32_t used = embedded::stackUsedSincePaint();
    if (used > figures.stackHighWater) figures.stackHighWater = used;
    return status;
  }
  mjukf::Status timeUpdate(Scalar t, Scalar h) {
    ++figures.measurementSteps;
    return measure(figures.measurementTicks, [&] { return filter.timeUpdate(t, h); });
  }
  mjukf::Status measurementUpdate(const typename Filter::Meas& y) {
    return measure(figures.measurementTicks, [&] { return filter.measurementUpdate(y); });
  }
  mjukf::Status propagateMean(Scalar t, Scalar h) {
    ++figures.openLoopSteps;
    return measure(figures.openLoopTicks, [&] { return filter.propagateMean(t, h); });
  }
};

template <class Scalar, class Filter>
void printEstimate(const char* name, long row, const Filter& filter) {
  Line line;
  line.text("est ").text(scalarName<Scalar>()).text(" ").text(name).text(" ").number(static_cast<std::uint64_t>(row));
  const auto x = filter.state();
  const auto theta = filter.parameters();
  for (int i = 0; i < x.size(); ++i) line.bits(x(i));
  for (int i = 0; i < theta.size(); ++i) line.bits(theta(i));
  line.write();
}

// Builds the filter from `settings` by its factory, refuses a broken copy of them first, runs it and
// prints what it did. True when everything went as expected.
template <class Scalar, class Filter, class Settings>
bool runFilter(const char* name, const typename Filter::Param& initialParameters, const Settings& settings) {
  using Experiment = mjukf::paper::FlexibleJointExperiment<Scalar>;
  using Model = typename Experiment::Model;

  // A filter without the health monitor is refused unless its settings say it is off (on by default).
  if constexpr (!Features::healthMonitor) {
    if (settings.health.enabled) {
      Settings unmonitored = settings;
      unmonitored.health.enabled = false;
      return runFilter<Scalar, Filter>(name, initialParameters, unmonitored);
    }
  }
  Settings broken = settings;
  broken.measurementNoise(0, 0) = Scalar(-1);
  const auto refused = Filter::create(Model(), Experiment::initialState(), initialParameters, broken);
  // a == b for NUL-terminated texts (newlib's strcmp would add 0.7 KB to every image with a filter).
  const auto sameText = [](const char* a, const char* b) {
    while (*a && *a == *b) ++a, ++b;
    return *a == *b;
  };
  const bool namesR = !refused && sameText(refused.error().setting, "measurementNoise (R)");
  if (!namesR) Line().text("error: ").text(name).text(" accepted a negative R or named another setting").write();

  auto made = Filter::create(Model(), Experiment::initialState(), initialParameters, settings);
  if (!made) {
    const mjukf::SettingsError& e = made.error();
    Line().text("settings error: ").text(e.owner).text(": setting '").text(e.setting).text("' ").text(e.reason).write();
    return false;
  }
  Filter& filter = *made;
  Plant<Scalar> plant;
  Figures figures;
  Measured<Filter> measured{filter, figures};
  const mjukf::paper::ScheduleOutcome outcome = mjukf::paper::runSchedule(
      measured, kRows, Experiment::stepSize, Experiment::measurementEvery,
      [&](long row) -> const typename Model::Meas& { return plant.measurementAt(row); },
      [&](long row, const Measured<Filter>& m) {
        if (row % kPrintEvery == 0) printEstimate<Scalar>(name, row, m.filter);
      });
  Line()
      .text("fig ")
      .text(scalarName<Scalar>())
      .text(" ")
      .text(name)
      .text(" sizeof ")
      .number(sizeof(Filter))
      .text(" measurementTicks ")
      .number(figures.measurementTicks)
      .text(" measurementSteps ")
      .number(static_cast<std::uint64_t>(figures.measurementSteps))
      .text(" openLoopTicks ")
      .number(figures.openLoopTicks)
      .text(" openLoopSteps ")
      .number(static_cast<std::uint64_t>(figures.openLoopSteps))
      .text(" stack ")
      .number(figures.stackHighWater)
      .text(" status ")
      .text(mjukf::toString(outcome.status))
      .write();
  // The parameter estimates end near the truth: within 15 %, where the first guess is ~30 % off and the
  // measured runs stay within ±7 % over their last 10 s (docs/embedded.md).
  const typename Model::Param truth = Model::trueParameters();
  const typename Model::Param error = (filter.parameters() - truth).cwiseQuotient(truth);
  const bool converged = error.cwiseAbs().maxCoeff() <= Scalar(0.15);
  if (!converged) Line().text("error: ").text(name).text(" ended with parameters more than 15 % off").write();
  return namesR && converged && outcome.status == mjukf::Status::Ok;
}

template <class Scalar>
bool runAll() {
  using Experiment = mjukf::paper::FlexibleJointExperiment<Scalar>;
  using Model = typename Experiment::Model;
  using Stepper = mjukf::DefaultIntegrator<Model>;
  using mjukf::MerweScaled, mjukf::FullCovariance, mjukf::SquareRootCovariance;
  bool ok = true;
  if constexpr ((EMBEDDED_FILTERS & 1) != 0)
    ok &= runFilter<Scalar, mjukf::Ukf<Model, Stepper, MerweScaled, FullCovariance, Features>>(
        "ukf", Model::trueParameters(), Experiment::ukf());
  if constexpr ((EMBEDDED_FILTERS & 2) != 0)
    ok &= runFilter<Scalar, mjukf::JointUkf<Model, Stepper, MerweScaled, FullCovariance, Features>>(
        "jukf", Experiment::initialParameters(), Experiment::jointUkf());
  if constexpr ((EMBEDDED_FILTERS & 4) != 0)
    ok &= runFilter<Scalar, mjukf::ModifiedJointUkf<Model, Stepper, MerweScaled, FullCovariance, Features>>(
        "mjukf", Experiment::initialParameters(), Experiment::modifiedJointUkf());
  if constexpr ((EMBEDDED_FILTERS & 8) != 0)
    ok &= runFilter<Scalar, mjukf::DualUkf<Model, Stepper, MerweScaled, FullCovariance, Features>>(
        "dual", Experiment::initialParameters(), Experiment::dualUkf());
  if constexpr ((EMBEDDED_FILTERS & 16) != 0)
    ok &= runFilter<Scalar, mjukf::Ukf<Model, Stepper, MerweScaled, SquareRootCovariance, Features>>(
        "ukf_sr", Model::trueParameters(), Experiment::ukf());
  if constexpr ((EMBEDDED_FILTERS & 32) != 0)
    ok &= runFilter<Scalar, mjukf::JointUkf<Model, Stepper, MerweScaled, SquareRootCovariance, Features>>(
        "jukf_sr", Experiment::initialParameters(), Experiment::jointUkf());
  if constexpr ((EMBEDDED_FILTERS & 64) != 0)
    ok &= runFilter<Scalar, mjukf::ModifiedJointUkf<Model, Stepper, MerweScaled, SquareRootCovariance, Features>>(
        "mjukf_sr", Experiment::initialParameters(), Experiment::modifiedJointUkf());
  if constexpr ((EMBEDDED_FILTERS & 128) != 0)
    ok &= runFilter<Scalar, mjukf::DualUkf<Model, Stepper, MerweScaled, SquareRootCovariance, Features>>(
        "dual_sr", Experiment::initialParameters(), Experiment::dualUkf());
  if constexpr (EMBEDDED_FILTERS == 0) {  // the baseline: the plant and the output alone
    Plant<Scalar> plant;
    Line line;
    line.text("est ").text(scalarName<Scalar>()).text(" plant ").number(static_cast<std::uint64_t>(kRows - 1));
    const auto& y = plant.measurementAt(kRows - 1);
    for (int j = 0; j < y.size(); ++j) line.bits(y(j));
    line.write();
  }
  return ok;
}

}  // namespace

int embedded::programMain() {
  // The clock's scale: a loop of a known number of instructions (0 ticks on the host).
  constexpr std::uint32_t kLoops = 1000000;
  Line().text("clock instructions ").number(2 * kLoops).text(" ticks ").number(embedded::ticksOfLoop(kLoops)).write();
  bool ok = runAll<float>();
#ifdef EMBEDDED_DOUBLE_REFERENCE
  ok &= runAll<double>();
#endif
  Line().text("heap calls ").number(embedded::heapCalls()).write();
  ok &= embedded::heapCalls() == 0;
  Line().text(ok ? "ok" : "FAILED").write();
  return ok ? 0 : 1;
}
