// Your own model, start to finish: docs/getting-started.md walks through this program, and the README
// quotes it (tests/docs keeps the quote in step with this file).
//
//   your_own_model [rk4|itrbdf2] [parameter process noise] [seed]      (defaults: rk4 0 1)
//
// BEGIN README EXAMPLE
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <mjukf/mjukf.hpp>

// The Van der Pol oscillator with an unknown damping μ: ẋ₁ = x₂, ẋ₂ = μ (1 − x₁²) x₂ − x₁.
// Only the position x₁ is measured. No input: InputDim = 0 and no input(t) function.
struct VanDerPol {
  using Scalar = double;
  static constexpr int StateDim = 2, ParamDim = 1, MeasDim = 1, InputDim = 0;
  using State = Eigen::Matrix<double, StateDim, 1>;
  using Param = Eigen::Matrix<double, ParamDim, 1>;
  using Meas = Eigen::Matrix<double, MeasDim, 1>;
  using Input = Eigen::Matrix<double, InputDim, 1>;

  State derivative(double /*t*/, const State& x, const Input& /*u*/, const Param& mu) const {
    return State(x(1), mu(0) * (1 - x(0) * x(0)) * x(1) - x(0));
  }
  Meas measurement(const State& x, const Param& /*mu*/) const { return Meas(x(0)); }
};

// Estimates μ with the joint UKF and a stepper chosen on purpose: leaving it out gives the paper's
// I-TR-BDF2, which is first order and costs accuracy at this coarse step.
template <class Stepper>
int run(double parameterProcessNoise, unsigned seed) {
  const double h = 0.1, sigma = 0.1, trueMu = 1.0;  // step (s), measurement noise, the truth
  const int steps = 600;                            // 60 s, a measurement every step

  // Measurements: the true plant simulated with a fine RK4 step, plus noise.
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<double> y(steps + 1);
  std::vector<VanDerPol::State> truth(steps + 1);
  mjukf::simulate(VanDerPol(), mjukf::Rk4<double>(), VanDerPol::State(2, 0), VanDerPol::Param(trueMu), 0.0, h / 20,
                  20 * steps, [&](long k, double, const VanDerPol::State& x) {
                    if (k % 20 != 0) return;
                    truth[k / 20] = x;
                    y[k / 20] = x(0) + noise(rng);
                  });

  mjukf::JointUkfSettingsFor<VanDerPol> settings;  // P₀ and Q cover [x; μ]
  settings.initialCovariance.diagonal() << 0.1, 0.1, 1.0;
  settings.processNoise.diagonal() << 1e-4, 1e-4, parameterProcessNoise;
  settings.measurementNoise << sigma * sigma;
  mjukf::JointUkf<VanDerPol, Stepper> filter(VanDerPol(), VanDerPol::State(2, 0), VanDerPol::Param(0.5), settings);

  double squaredStateError = 0, squaredMuError = 0;
  for (int k = 0; k < steps; ++k) {
    mjukf::Status status = filter.timeUpdate(k * h, h);  // no input argument: the model has none
    if (mjukf::taken(status)) status = filter.measurementUpdate(VanDerPol::Meas(y[k + 1]));
    if (!mjukf::taken(status)) {  // the filter is as it was before the call; see docs/troubleshooting.md
      std::printf("step %d refused: %s\n", k, mjukf::toString(status));
      return 1;
    }
    squaredStateError += (filter.state() - truth[k + 1]).squaredNorm() / steps;
    if (k >= steps / 2) squaredMuError += std::pow(filter.parameters()(0) - trueMu, 2) / (steps - steps / 2);
  }
  std::printf("mu = %.4f +- %.4f (true %.1f)\n", filter.parameters()(0), std::sqrt(filter.covariance()(2, 2)), trueMu);
  std::printf("RMSE: state %.4f, mu over the last 30 s %.4f\n", std::sqrt(squaredStateError),
              std::sqrt(squaredMuError));
  return 0;
}

int main(int argc, char** argv) {
  const std::string stepper = argc > 1 ? argv[1] : "rk4";
  const double parameterProcessNoise = argc > 2 ? std::stod(argv[2]) : 0.0;
  const unsigned seed = argc > 3 ? unsigned(std::stoul(argv[3])) : 1;
  if (stepper == "rk4") return run<mjukf::Rk4<double>>(parameterProcessNoise, seed);
  if (stepper == "itrbdf2") return run<mjukf::ITrBdf2<double>>(parameterProcessNoise, seed);
  std::printf("usage: your_own_model [rk4|itrbdf2] [parameter process noise] [seed]\n");
  return 2;
}
// END README EXAMPLE
