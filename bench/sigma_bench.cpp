// sigma/<L>/<scalar>: drawing the 2L + 1 sigma points of a mean and covariance (one Cholesky
// factorisation and the columns), and ut/<L>/<scalar>: the weighted mean and covariance of a point set.

#include <random>
#include <string>

#include <benchmark/benchmark.h>

#include "mjukf/sigma_points.hpp"
#include "mjukf/unscented_transform.hpp"

namespace {

template <class Scalar>
const char* scalarName() {
  return sizeof(Scalar) == sizeof(float) ? "float" : "double";
}

// A correlated, well-conditioned covariance, the same on every run.
template <class Scalar, int L>
Eigen::Matrix<Scalar, L, L> covariance() {
  std::mt19937_64 rng(42);
  std::normal_distribution<double> normal;
  Eigen::Matrix<double, L, L> factor;
  for (int r = 0; r < L; ++r)
    for (int c = 0; c < L; ++c) factor(r, c) = normal(rng);
  return (factor * factor.transpose() + Eigen::Matrix<double, L, L>::Identity()).template cast<Scalar>();
}

template <class Scalar, int L>
void sigmaPoints(benchmark::State& state) {
  mjukf::MerweScaledSigmaPoints<Scalar, L> sigma;
  const Eigen::Matrix<Scalar, L, 1> mean = Eigen::Matrix<Scalar, L, 1>::LinSpaced(Scalar(-1), Scalar(1));
  const Eigen::Matrix<Scalar, L, L> cov = covariance<Scalar, L>();
  typename mjukf::MerweScaledSigmaPoints<Scalar, L>::Points points;
  for (auto _ : state) {
    benchmark::DoNotOptimize(sigma.generate(mean, cov, points));
    benchmark::DoNotOptimize(points.data());
    benchmark::ClobberMemory();
  }
  state.counters["points"] = 2 * L + 1;
}

template <class Scalar, int L>
void unscentedTransform(benchmark::State& state) {
  mjukf::MerweScaledSigmaPoints<Scalar, L> sigma;
  const Eigen::Matrix<Scalar, L, 1> mean = Eigen::Matrix<Scalar, L, 1>::LinSpaced(Scalar(-1), Scalar(1));
  typename mjukf::MerweScaledSigmaPoints<Scalar, L>::Points points;
  if (sigma.generate(mean, covariance<Scalar, L>(), points) != mjukf::Status::Ok) {
    state.SkipWithError("no sigma points");
    return;
  }
  Eigen::Matrix<Scalar, L, 1> outMean;
  Eigen::Matrix<Scalar, L, L> outCov;
  for (auto _ : state) {
    benchmark::DoNotOptimize(points.data());
    mjukf::unscentedTransform(points, sigma.meanWeights(), sigma.covarianceWeights(), outMean, outCov);
    benchmark::DoNotOptimize(outMean.data());
    benchmark::DoNotOptimize(outCov.data());
    benchmark::ClobberMemory();
  }
  state.counters["points"] = 2 * L + 1;
}

template <class Scalar, int L>
void registerDimension() {
  const std::string suffix = "/" + std::to_string(L) + "/" + scalarName<Scalar>();
  benchmark::RegisterBenchmark(("sigma" + suffix).c_str(), sigmaPoints<Scalar, L>);
  benchmark::RegisterBenchmark(("ut" + suffix).c_str(), unscentedTransform<Scalar, L>);
}

template <class Scalar>
void registerScalar() {
  registerDimension<Scalar, 2>();
  registerDimension<Scalar, 4>();
  registerDimension<Scalar, 6>();
  registerDimension<Scalar, 8>();
  registerDimension<Scalar, 12>();
}

const bool registered = [] {
  registerScalar<float>();
  registerScalar<double>();
  return true;
}();

}  // namespace
