// Fingerprints of every filter's trajectory on the reference files: an FNV-1a hash of the bytes of the
// state, covariance, parameters, status and diagnostics after every step, for each filter (UKF with
// I-TR-BDF2 and RK4, JUKF, MJUKF hand-tuned and automatic, dual in both orderings), reference file and
// variant (plain; masked updates with NaN in the missing channel; NaN and huge measurements refused;
// redrawn points; χ² gate with active bounds; multi-step time updates; held input; a reset halfway),
// in double and (robot) float. Two versions of the library whose fingerprints agree computed the same
// bits. scripts/fingerprint.sh builds this program against two versions and compares: the check that a
// refactoring changed no result. It is not a ctest: it needs two builds.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "mjukf/mjukf.hpp"
#if __has_include("paper/paper.hpp")
#include "paper/paper.hpp"  // examples/support/
#else
#include "mjukf/paper/paper.hpp"  // before 0.2.0
#endif

namespace {

struct Hash {
  std::uint64_t h = 1469598103934665603ull;
  void bytes(const void* p, std::size_t n) {
    const auto* c = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ c[i]) * 1099511628211ull;
  }
  template <class M>
  void matrix(const M& m) {
    typename M::PlainObject plain = m;
    bytes(plain.data(), sizeof(typename M::Scalar) * std::size_t(plain.size()));
  }
  void scalar(double v) { bytes(&v, sizeof v); }
  void integer(int v) { bytes(&v, sizeof v); }
};

std::vector<std::vector<double>> readY(const std::string& path, int m, long maxRows) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line) && long(rows.size()) < maxRows) {
    std::stringstream ss(line);
    std::string cell;
    std::getline(ss, cell, ',');
    std::vector<double> y;
    for (int j = 0; j < m; ++j) {
      std::getline(ss, cell, ',');
      y.push_back(std::stod(cell));
    }
    rows.push_back(y);
  }
  return rows;
}

template <class F, class = void>
struct HasPoints : std::false_type {};
template <class F>
struct HasPoints<F, std::void_t<decltype(std::declval<const F&>().parameterPoints())>> : std::true_type {};
template <class F, class = void>
struct HasParamCov : std::false_type {};
template <class F>
struct HasParamCov<F, std::void_t<decltype(std::declval<const F&>().parameterCovariance())>> : std::true_type {};

template <class F>
void record(Hash& hash, const F& f, mjukf::Status s) {
  hash.integer(int(s));
  hash.matrix(f.state());
  hash.matrix(f.covariance());
  hash.matrix(f.parameters());
  hash.matrix(f.lastUpdate().innovation);
  hash.matrix(f.lastUpdate().innovationCovariance);
  hash.scalar(double(f.lastUpdate().nis));
  if constexpr (HasPoints<F>::value) hash.matrix(f.parameterPoints());
  if constexpr (HasParamCov<F>::value) hash.matrix(f.parameterCovariance());
}

enum class Variant { Plain, Masked, Refusals, Redraw, GateBounds, MultiStep, Held, Reset };
const char* name(Variant v) {
  switch (v) {
    case Variant::Plain: return "plain";
    case Variant::Masked: return "masked";
    case Variant::Refusals: return "refusals";
    case Variant::Redraw: return "redraw";
    case Variant::GateBounds: return "gate+bounds";
    case Variant::MultiStep: return "multistep";
    case Variant::Held: return "held";
    case Variant::Reset: return "reset";
  }
  return "?";
}

// The dual filter's reset also takes P^θ; the JUKF's and MJUKF's take θ̂ only (their parameterCovariance()
// is read, not set).
template <class F, class = void>
struct ResetsParamCov : std::false_type {};
template <class F>
struct ResetsParamCov<F, std::void_t<decltype(std::declval<F&>().reset(
                             std::declval<const F&>().state(), std::declval<const F&>().covariance(),
                             std::declval<const F&>().parameters(), std::declval<const F&>().parameterCovariance()))>>
    : std::true_type {};

template <class F>
void resetHalfway(F& f) {
  if constexpr (ResetsParamCov<F>::value)
    (void)f.reset(f.state(), f.covariance(), f.parameters(), f.parameterCovariance());
  else
    (void)f.reset(f.state(), f.covariance(), f.parameters());
}

template <class Filter, class Experiment>
void run(const char* fileName, const char* filterName, Variant variant, Filter f,
         const std::vector<std::vector<double>>& data) {
  using Model = typename Experiment::Model;
  using Meas = typename Model::Meas;
  using Scalar = typename Model::Scalar;
  constexpr int m = Model::MeasDim;
  const Scalar h = Experiment::stepSize;
  const int every = Experiment::measurementEvery;
  Hash hash;
  long refused = 0;
  record(hash, f, mjukf::Status::Ok);
  const long rows = long(data.size());
  for (long k = 0; k + 1 < rows; ++k) {
    const Scalar t = Scalar(k) * h;
    mjukf::Status s = mjukf::Status::Ok;
    if ((k + 1) % every == 0) {
      Meas y;
      for (int j = 0; j < m; ++j) y(j) = Scalar(data[std::size_t(k + 1)][std::size_t(j)]);
      if (variant == Variant::MultiStep) {
        s = f.timeUpdate(t - Scalar(every - 1) * h, h, every);
      } else if (variant == Variant::Held) {
        typename Model::Input u = f.model().input(t);
        s = f.timeUpdate(t, h, u);
      } else {
        s = f.timeUpdate(t, h);
      }
      record(hash, f, s);
      if (variant == Variant::Masked && (k + 1) % (7 * every) == 0) {
        mjukf::MeasurementMask<m> present = mjukf::MeasurementMask<m>::Constant(true);
        present(0) = false;
        y(0) = std::numeric_limits<Scalar>::quiet_NaN();
        s = f.measurementUpdate(y, present);
      } else if (variant == Variant::Refusals && (k + 1) % (11 * every) == 0) {
        y(0) = std::numeric_limits<Scalar>::quiet_NaN();
        s = f.measurementUpdate(y);
      } else if (variant == Variant::Refusals && (k + 1) % (13 * every) == 0) {
        y(0) = Scalar(1e300 > double(std::numeric_limits<Scalar>::max()) ? std::numeric_limits<Scalar>::max() : 1e300);
        s = f.measurementUpdate(y);
      } else {
        s = f.measurementUpdate(y);
      }
    } else if (variant != Variant::MultiStep) {
      if (variant == Variant::Held) {
        typename Model::Input u = f.model().input(t);
        s = f.propagateMean(t, h, u);
      } else {
        s = f.propagateMean(t, h);
      }
    }
    if (variant == Variant::Reset && k + 1 == rows / 2) resetHalfway(f);
    refused += !mjukf::taken(s);
    record(hash, f, s);
  }
  std::printf("%-40s %-12s %-12s %016llx refused=%ld p=%.17g\n", fileName, filterName, name(variant),
              (unsigned long long)hash.h, refused, double(f.parameters()(0)));
}

template <class F, class = void>
struct HasBounds : std::false_type {};
template <class F>
struct HasBounds<F, std::void_t<decltype(std::declval<F&>().parameterBounds)>> : std::true_type {};

template <class Experiment, class Settings>
Settings withVariant(Settings s, Variant v, bool bounds) {
  using Model = typename Experiment::Model;
  if (v == Variant::Redraw) s.redrawPointsForUpdate = true;
  if (v == Variant::GateBounds) {
    s.gate = decltype(s.gate)::chiSquare(0.999);
    if constexpr (HasBounds<Settings>::value) {
      if (bounds) {
        s.parameterBounds.lower = Experiment::initialParameters() * typename Model::Scalar(0.5);
        s.parameterBounds.upper = Experiment::initialParameters() * typename Model::Scalar(1.5);
      }
    }
  }
  return s;
}

template <class Experiment>
void runAll(const char* fileName, const std::string& dir, long maxRows) {
  using Model = typename Experiment::Model;
  using Scalar = typename Model::Scalar;
  const auto data = readY(dir + "/" + fileName, Model::MeasDim, maxRows);
  const Model model;
  const auto x0 = Experiment::initialState();
  const auto th0 = Experiment::initialParameters();
  const auto truth = Model::trueParameters();
  for (Variant v : {Variant::Plain, Variant::Masked, Variant::Refusals, Variant::Redraw, Variant::GateBounds,
                    Variant::MultiStep, Variant::Held, Variant::Reset}) {
    if constexpr (Model::InputDim == 0)
      if (v == Variant::Held) continue;
    {
      auto s = withVariant<Experiment>(Experiment::ukf(), v, false);
      run<mjukf::Ukf<Model>, Experiment>(fileName, "ukf", v, mjukf::Ukf<Model>(model, x0, truth, s), data);
      run<mjukf::Ukf<Model, mjukf::Rk4<Scalar>>, Experiment>(
          fileName, "ukf-rk4", v, mjukf::Ukf<Model, mjukf::Rk4<Scalar>>(model, x0, truth, s), data);
    }
    {
      auto s = withVariant<Experiment>(Experiment::jointUkf(), v, true);
      run<mjukf::JointUkf<Model>, Experiment>(fileName, "jukf", v, mjukf::JointUkf<Model>(model, x0, th0, s), data);
    }
    {
      auto s = withVariant<Experiment>(Experiment::modifiedJointUkf(), v, true);
      run<mjukf::ModifiedJointUkf<Model>, Experiment>(fileName, "mjukf", v,
                                                      mjukf::ModifiedJointUkf<Model>(model, x0, th0, s), data);
      s.automaticTransformation = true;
      s.adaptiveScaling = true;
      run<mjukf::ModifiedJointUkf<Model>, Experiment>(fileName, "mjukf-auto", v,
                                                      mjukf::ModifiedJointUkf<Model>(model, x0, th0, s), data);
    }
    {
      auto s = withVariant<Experiment>(Experiment::dualUkf(), v, true);
      run<mjukf::DualUkf<Model>, Experiment>(fileName, "dual-prior", v, mjukf::DualUkf<Model>(model, x0, th0, s), data);
      s.ordering = mjukf::DualUkfOrdering::UpdatedParameters;
      run<mjukf::DualUkf<Model>, Experiment>(fileName, "dual-updated", v, mjukf::DualUkf<Model>(model, x0, th0, s),
                                             data);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : "data";
  using Robot = mjukf::paper::FlexibleJointExperiment<double>;
  using Tank = mjukf::paper::CoupledTankExperiment<double>;
  using RobotF = mjukf::paper::FlexibleJointExperiment<float>;
  runAll<Robot>("flexible_joint_reference.csv", dir, 20001);
  runAll<Robot>("flexible_joint_param_change_reference.csv", dir, 30001);
  runAll<Tank>("coupled_tank_reference.csv", dir, 60001);
  runAll<RobotF>("flexible_joint_reference.csv", dir, 20001);
  return 0;
}
