// kernel/<kernel>/<form>/<scalar>/<L>: each kernel of detail/linear_algebra.hpp that is chosen by size,
// in each of its forms, on an L-dimensional point set of 2L + 1 points (a filter of augmented dimension
// L): the threshold `generalKernelsFrom` is the smallest L from which the general form is faster.
//   covariance: P = Σ Wᵢ dᵢ dᵢᵀ (L × L) — coefficientwise, blocks (the library's general form: one
//     triangle by register blocks, mirrored), and Eigen's forms, the general ones until blocks: triangle
//     (its product into one triangle, mirrored), gemm (both triangles: the general product as Eigen picks it);
//   cross: P_xy = Σ Wᵢ dᵢ eᵢᵀ (L × ⌈L/2⌉, the chain's m = n/2) — coefficientwise, blocks, product (Eigen's);
//   subtract: P − U Uᵀ (U L × ⌈L/2⌉) — coefficientwise, blocks (one triangle, mirrored), rank_update
//     (Eigen's, one triangle, mirrored), gemm (Eigen's, both triangles);
//   cholesky: S Sᵀ = P — unrolled, blocked (Eigen's in-place LLT: the general form until `columns`),
//     columns (a matrix-vector product per column).
// scripts/scaling.sh runs it and writes the table of docs/performance-scaling.md.

#include <random>
#include <string>

#include <Eigen/Cholesky>
#include <benchmark/benchmark.h>

#include "mjukf/detail/linear_algebra.hpp"

namespace mjukf::bench {
namespace {

namespace la = mjukf::detail;

template <class Scalar, int L>
struct KernelInputs {
  static constexpr int Count = 2 * L + 1;
  static constexpr int M = (L + 1) / 2;
  Eigen::Matrix<Scalar, L, Count> d;
  Eigen::Matrix<Scalar, M, Count> e;
  Eigen::Matrix<Scalar, Count, 1> w;
  Eigen::Matrix<Scalar, L, L> p, factor;
  Eigen::Matrix<Scalar, L, M> u;
  Eigen::Matrix<Scalar, L, M> cross;

  KernelInputs() {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> normal;
    for (int c = 0; c < Count; ++c) {
      for (int r = 0; r < L; ++r) d(r, c) = Scalar(normal(rng));
      for (int r = 0; r < M; ++r) e(r, c) = Scalar(normal(rng));
    }
    // van der Merwe's weights with α = 1, β = 2, κ = 0: W₀ = 2, Wᵢ = 1/(2L).
    w.setConstant(Scalar(1) / Scalar(2 * L));
    w(0) = Scalar(2);
    Eigen::Matrix<Scalar, L, L> a;
    for (int c = 0; c < L; ++c)
      for (int r = 0; r < L; ++r) a(r, c) = Scalar(normal(rng));
    p = a * a.transpose() + Scalar(L) * Eigen::Matrix<Scalar, L, L>::Identity();
    // U small against P, so that P − U Uᵀ stays positive definite over the repetitions' restarts.
    for (int c = 0; c < M; ++c)
      for (int r = 0; r < L; ++r) u(r, c) = Scalar(0.01 * normal(rng));
  }
};

template <class Scalar, int L, int Form>
void covariance(benchmark::State& state) {
  KernelInputs<Scalar, L> in;
  for (auto _ : state) {
    benchmark::DoNotOptimize(in.d.data());
    if constexpr (Form == 0)
      la::weightedCovarianceLowerCoefficientwise(in.d, in.w, in.p);
    else if constexpr (Form == 1)
      in.p.template triangularView<Eigen::Lower>() = (in.d * in.w.asDiagonal()) * in.d.transpose();
    else if constexpr (Form == 2)
      in.p.noalias() = (in.d * in.w.asDiagonal()) * in.d.transpose();
    else
      la::weightedCovarianceLowerTriangle(in.d, in.w, in.p);
    la::mirrorLowerTriangle(in.p);
    benchmark::DoNotOptimize(in.p.data());
    benchmark::ClobberMemory();
  }
}

template <class Scalar, int L, int Form>
void cross(benchmark::State& state) {
  KernelInputs<Scalar, L> in;
  for (auto _ : state) {
    benchmark::DoNotOptimize(in.d.data());
    if constexpr (Form == 0)
      la::weightedOuterSumCoefficientwise(in.d, in.e, in.w, in.cross);
    else if constexpr (Form == 1)
      in.cross.noalias() = (in.d * in.w.asDiagonal()) * in.e.transpose();
    else
      la::weightedOuterSumProduct(in.d, in.e, in.w, in.cross);
    benchmark::DoNotOptimize(in.cross.data());
    benchmark::ClobberMemory();
  }
}

template <class Scalar, int L, int Form>
void subtract(benchmark::State& state) {
  KernelInputs<Scalar, L> in;
  const Eigen::Matrix<Scalar, L, L> prior = in.p;
  for (auto _ : state) {
    in.p = prior;  // as the engine does: P = P⁻, then P −= U Uᵀ
    benchmark::DoNotOptimize(in.u.data());
    if constexpr (Form == 0) {
      la::subtractOuterCoefficientwise(in.p, in.u);
    } else if constexpr (Form == 1) {
      in.p.template selfadjointView<Eigen::Lower>().rankUpdate(in.u, Scalar(-1));
      la::mirrorLowerTriangle(in.p);
    } else if constexpr (Form == 2) {
      in.p.noalias() -= in.u * in.u.transpose();
    } else {
      la::subtractOuterRankUpdate(in.p, in.u);
    }
    benchmark::DoNotOptimize(in.p.data());
    benchmark::ClobberMemory();
  }
}

template <class Scalar, int L, int Form>
void cholesky(benchmark::State& state) {
  KernelInputs<Scalar, L> in;
  for (auto _ : state) {
    benchmark::DoNotOptimize(in.p.data());
    bool ok;
    if constexpr (Form == 0) {
      ok = la::choleskyLowerUnrolled(in.p, in.factor);
    } else if constexpr (Form == 1) {  // the general form until the one by columns: Eigen's blocked in-place LLT
      in.factor.template triangularView<Eigen::Lower>() = in.p;
      ok = Eigen::internal::llt_inplace<Scalar, Eigen::Lower>::blocked(in.factor) < 0;
    } else {
      ok = la::choleskyLowerByColumns(in.p, in.factor);
    }
    if (!ok) {
      state.SkipWithError("not positive definite");
      break;
    }
    benchmark::DoNotOptimize(in.factor.data());
    benchmark::ClobberMemory();
  }
}

template <class Scalar, int L>
void registerSize() {
  const std::string suffix =
      std::string("/") + (std::is_same_v<Scalar, float> ? "float" : "double") + "/" + std::to_string(L);
  benchmark::RegisterBenchmark(("kernel/covariance/coefficientwise" + suffix).c_str(), covariance<Scalar, L, 0>);
  benchmark::RegisterBenchmark(("kernel/covariance/triangle" + suffix).c_str(), covariance<Scalar, L, 1>);
  benchmark::RegisterBenchmark(("kernel/covariance/gemm" + suffix).c_str(), covariance<Scalar, L, 2>);
  benchmark::RegisterBenchmark(("kernel/covariance/blocks" + suffix).c_str(), covariance<Scalar, L, 3>);
  benchmark::RegisterBenchmark(("kernel/cross/coefficientwise" + suffix).c_str(), cross<Scalar, L, 0>);
  benchmark::RegisterBenchmark(("kernel/cross/product" + suffix).c_str(), cross<Scalar, L, 1>);
  benchmark::RegisterBenchmark(("kernel/cross/blocks" + suffix).c_str(), cross<Scalar, L, 2>);
  benchmark::RegisterBenchmark(("kernel/subtract/coefficientwise" + suffix).c_str(), subtract<Scalar, L, 0>);
  benchmark::RegisterBenchmark(("kernel/subtract/rank_update" + suffix).c_str(), subtract<Scalar, L, 1>);
  benchmark::RegisterBenchmark(("kernel/subtract/gemm" + suffix).c_str(), subtract<Scalar, L, 2>);
  benchmark::RegisterBenchmark(("kernel/subtract/blocks" + suffix).c_str(), subtract<Scalar, L, 3>);
  benchmark::RegisterBenchmark(("kernel/cholesky/unrolled" + suffix).c_str(), cholesky<Scalar, L, 0>);
  benchmark::RegisterBenchmark(("kernel/cholesky/blocked" + suffix).c_str(), cholesky<Scalar, L, 1>);
  benchmark::RegisterBenchmark(("kernel/cholesky/columns" + suffix).c_str(), cholesky<Scalar, L, 2>);
}

template <class Scalar, int... L>
void registerSizes(std::integer_sequence<int, L...>) {
  (registerSize<Scalar, L>(), ...);
}

// L = 2 … 16 one by one (the threshold lies there), then the chain's larger augmented dimensions.
using Sizes = std::integer_sequence<int, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 20, 24, 28, 32, 36>;

const bool registered = [] {
  registerSizes<double>(Sizes());
  registerSizes<float>(Sizes());
  return true;
}();

}  // namespace
}  // namespace mjukf::bench
