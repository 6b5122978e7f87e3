#pragma once

// The small linear algebra of a filter step, in one place: the finiteness check, the Cholesky factor
// and triangular solves, LU with partial pivoting, the symmetrisation of a covariance, the weighted
// moments of a point set (the unscented transform, docs/algorithms.md §1–3), the symmetric sigma-point
// draw, and the square-root factors of the square-root form (docs/algorithms.md §10: Householder factors
// of B Bᵀ and AᵀA, rank-one updates and downdates of a Cholesky factor, a square root of a semi-definite
// matrix), and the positive semi-definite part of a symmetric matrix (the MJUKF's floor of P⁻, §5.2).
// Every function takes fixed-size Eigen matrices, writes into its arguments and allocates nothing (one
// exception: above 16 × 16, partialPivotLu is Eigen's blocked LU, whose general product takes its buffers
// from the stack by alloca where the platform has it and from the heap where it has not); each is written
// out where Eigen's general path costs more than the arithmetic at these sizes (said at each).

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Jacobi>
#include <Eigen/LU>

// GCC and Clang: inline every call made in the function, recursively (what the compiler can see).
// The propagation of the points is the bulk of a step, and left to its own budget the compiler keeps
// the stepper, the model's derivative and Eigen's 4-vector assignments as separate calls there, which
// costs a third more than the same arithmetic inlined (bench/: step against floor). The small weighted
// sums below too: on the Cortex-M4F, -O2 kept each coefficient's sum as a call to Eigen's evaluator,
// which built its arguments on the stack (docs/embedded.md). Not when optimising for size (-Os,
// firmware): there the calls are what the build asked for.
#if (defined(__GNUC__) || defined(__clang__)) && !defined(__OPTIMIZE_SIZE__)
#define MJUKF_FLATTEN __attribute__((flatten))
#else
#define MJUKF_FLATTEN
#endif

namespace mjukf::detail {

// ---- Kernels chosen by size ----------------------------------------------------------------------------
//
// The weighted outer sums, P − U Uᵀ and the Cholesky factor below are written out coefficient by
// coefficient (fully unrolled for the factor), which is fastest at the sizes of the paper's plants but
// grows as L³ and stops using the vector units well: at L = 36 the outer sums were half of a step. From
// a size on, each takes a general form instead: the products a product by register blocks
// (productWithTranspose; one triangle for a covariance and for P − U Uᵀ), the factor a factorisation by
// columns (one of Eigen's matrix-vector products each). The sizes are where the general form measured
// faster and stayed so (`mjukf_kernel_bench`, each kernel in each form at L = 2 … 16, 20, 24, 28, 32, 36;
// docs/performance-scaling.md says which are a size or two off the CPU-time border), per scalar type,
// with one exception: the double Cholesky, whose unrolled form stayed up to 10 % faster than Eigen's
// blocked LLT up to L = 32 but whose code and compile time grow as L³, is general from 20. They were
// measured with Eigen's forms as the general ones (its GEMM, its product into one triangle, its rank-k
// update, its blocked LLT); the register blocks, which form the same sums without packing them first,
// and the factor by columns took less time or fewer instructions at every size measured since, and the
// sizes were not measured again. The choice is made at compile time on the fixed size L (for a point
// set, of its 2L + 1 or 2L points). MJUKF_GENERAL_KERNELS_FROM overrides them all (scripts/scaling.sh
// builds the small-size kernels at every size with it).
struct GeneralKernelSizes {
  int covarianceProduct;   // Σ Wᵢ dᵢ dᵢᵀ by register blocks (measured as GEMM, both triangles)
  int covarianceTriangle;  // the MJUKF's covariance of θ̂ by blocks and one triangle (measured as Eigen's
                           // product into one triangle)
  int crossProduct;        // Σ Wᵢ aᵢ bᵢᵀ by register blocks (measured as GEMM)
  int subtractRankUpdate;  // P − U Uᵀ by register blocks, lower triangle, mirrored (measured as Eigen's
                           // rank-k update)
  int cholesky;            // the factor by columns (choleskyLowerByColumns)
};
#ifdef MJUKF_GENERAL_KERNELS_FROM
template <class Scalar>
inline constexpr GeneralKernelSizes generalKernelsFrom{MJUKF_GENERAL_KERNELS_FROM, MJUKF_GENERAL_KERNELS_FROM,
                                                       MJUKF_GENERAL_KERNELS_FROM, MJUKF_GENERAL_KERNELS_FROM,
                                                       MJUKF_GENERAL_KERNELS_FROM};
#else
template <class Scalar>
inline constexpr GeneralKernelSizes generalKernelsFrom =
    std::is_same_v<Scalar, float> ? GeneralKernelSizes{9, 28, 14, 24, 24} : GeneralKernelSizes{9, 20, 11, 20, 20};
#endif

// True when a kernel of fixed size N is at least `from` (a member of generalKernelsFrom).
template <int N>
constexpr bool atLeast(int from) {
  return N != Eigen::Dynamic && N >= from;
}

// ---- Finiteness ---------------------------------------------------------------------------------------

// True when no coefficient is NaN or ±Inf. Eigen's allFinite() compares x − x with itself and stops
// at the first mismatch: a branch per coefficient, which on a step's few dozen values costs more than
// the arithmetic it guards. Here x·0 is 0 for a finite x and NaN otherwise, and a sum is NaN as soon
// as one of its terms is, so the check is one vectorised reduction. (Like Eigen's, it needs IEEE
// arithmetic: -ffinite-math-only would let a compiler fold it to true.)
template <class Derived>
bool allFinite(const Eigen::DenseBase<Derived>& m) {
  using Scalar = typename Derived::Scalar;
  return (m.derived().array() * Scalar(0)).sum() == Scalar(0);
}

// True when every present component of y is finite (`present` null: all are present).
template <class Meas, class Mask>
bool presentComponentsFinite(const Meas& y, const Mask* present) {
  if (!present) return allFinite(y);
  for (int j = 0; j < y.size(); ++j)
    if ((*present)(j) && !std::isfinite(y(j))) return false;
  return true;
}

// ---- Cholesky factor and triangular solves ---------------------------------------------------------------
//
// The lower Cholesky factor of a small fixed-size matrix, written out instead of Eigen::LLT because
//  - an LLT member that was never computed holds an indeterminate `info()`, and copying it (copying
//    a filter before its first step) is undefined behaviour, which UBSan reports;
//  - Eigen's LLT also computes the matrix's L1 norm on every call (for rcond()), which nothing here
//    reads, and that is a measurable part of a step at these sizes.

// Calls f(std::integral_constant<int, I>()) for I = 0 … N − 1 in order while it returns true: a loop
// whose index is a compile-time constant, so that every loop below has a fixed trip count and the
// compiler unrolls all of them (nested loops whose bounds depend on an outer index are otherwise kept
// as loops, and at N = 4 their counters and branches cost as much as the arithmetic).
template <class F, int... I>
bool forEachIndexIn(F& f, std::integer_sequence<int, I...>) {
  return (f(std::integral_constant<int, I>()) && ...);
}
template <int N, class F>
bool forEachIndex(F&& f) {
  return forEachIndexIn(f, std::make_integer_sequence<int, N>());
}

// S with A = S Sᵀ, reading only the lower triangle of A (the strictly upper triangle of S is set to
// zero). Returns false, S then unspecified, when A is not numerically positive definite: a pivot
// a_jj − Σₖ s_jk² that is not above N ε a_jj, the size of its own rounding error, or not finite (NaN
// and Inf fail). Without that margin a singular A (0.5 everywhere, say) can pass on a pivot of 1e-16
// that is all rounding, and whether it passes then depends on the order of the sums: a P accepted here
// must also factor in any other correct Cholesky (Eigen's LLT), which the fuzz target checks.
// `s` must not alias `a`.
template <class Scalar, int N>
bool choleskyLowerUnrolled(const Eigen::Matrix<Scalar, N, N>& a, Eigen::Matrix<Scalar, N, N>& s) {
  // Computed as A = L D Lᵀ (L unit lower triangular), then S = L D^½. The pivots dⱼ are the squares of
  // the diagonal of S, and each column waits only for a division by the pivot before it, not for a
  // square root as well; the square roots are independent and come last. At these sizes the chain of
  // dependent divisions and roots is the cost of the factorisation.
  constexpr Scalar margin = Scalar(N) * std::numeric_limits<Scalar>::epsilon();
  Scalar inversePivot[N];
  const bool positive = forEachIndex<N>([&](auto jIndex) {
    constexpr int j = jIndex.value;
    // s(j, k) for k < j holds Lⱼₖ dₖ here; s(k, j) (upper triangle, free until the end) holds Lⱼₖ.
    Scalar pivot = a(j, j);
    forEachIndex<j>([&](auto k) { return pivot -= s(k.value, j) * s(j, k.value), true; });
    if (!(pivot > margin * a(j, j)) || !(pivot <= std::numeric_limits<Scalar>::max())) return false;  // NaN fails too
    s(j, j) = pivot;
    inversePivot[j] = Scalar(1) / pivot;
    forEachIndex<N - j - 1>([&](auto offset) {
      constexpr int i = j + 1 + offset.value;
      Scalar v = a(i, j);
      forEachIndex<j>([&](auto k) { return v -= s(k.value, i) * s(j, k.value), true; });
      s(i, j) = v;                    // Lᵢⱼ dⱼ
      s(j, i) = v * inversePivot[j];  // Lᵢⱼ
      return true;
    });
    return true;
  });
  if (!positive) return false;
  forEachIndex<N>([&](auto jIndex) {
    constexpr int j = jIndex.value;
    const Scalar root = std::sqrt(s(j, j));
    const Scalar inverseRoot = root * inversePivot[j];  // dⱼ^½ / dⱼ = dⱼ^-½
    forEachIndex<N - j - 1>([&](auto offset) { return s(j + 1 + offset.value, j) *= inverseRoot, true; });
    s(j, j) = root;
    forEachIndex<j>([&](auto i) { return s(i.value, j) = Scalar(0), true; });
    return true;
  });
  return true;
}

// The same factor and the same refusals, column by column (left-looking), for large N: column j is
// a_j − S_{j:,0:j} S_{j,0:j}ᵀ, one matrix-vector product, then scaled by the root of its pivot. The
// pivot is checked as in the unrolled form before its root is taken, so it stops at the first one not
// above the margin, and a NaN or Inf in the lower triangle of A reaches a later pivot through the column
// it enters. At N = 20 … 64 (a callgrind count, double and float) it took 3–36 % fewer instructions than
// Eigen's blocked in-place LLT, the form before, whose blocks of 8 are too small at these sizes to pay
// for its level-3 kernels (N = 36, double: about 35,000 against 55,000, and a third less time).
template <class Scalar, int N>
bool choleskyLowerByColumns(const Eigen::Matrix<Scalar, N, N>& a, Eigen::Matrix<Scalar, N, N>& s) {
  constexpr Scalar margin = Scalar(N) * std::numeric_limits<Scalar>::epsilon();
  s.template triangularView<Eigen::Lower>() = a;
  for (int j = 0; j < N; ++j) {
    if (j > 0) s.col(j).tail(N - j).noalias() -= s.block(j, 0, N - j, j) * s.row(j).head(j).transpose();
    const Scalar pivot = s(j, j);
    if (!(pivot > margin * a(j, j)) || !(pivot <= std::numeric_limits<Scalar>::max())) return false;  // NaN fails too
    const Scalar root = std::sqrt(pivot);
    s(j, j) = root;
    s.col(j).tail(N - j - 1) /= root;
  }
  s.template triangularView<Eigen::StrictlyUpper>().setZero();
  return true;
}

// S with A = S Sᵀ (choleskyLowerUnrolled's contract): the unrolled form for small N, the one by columns
// from generalKernelsFrom<Scalar>.cholesky on.
template <class Scalar, int N>
bool choleskyLower(const Eigen::Matrix<Scalar, N, N>& a, Eigen::Matrix<Scalar, N, N>& s) {
  if constexpr (atLeast<N>(generalKernelsFrom<Scalar>.cholesky))
    return choleskyLowerByColumns(a, s);
  else
    return choleskyLowerUnrolled(a, s);
}

// B ← S⁻¹ B and B ← S⁻ᵀ B for a lower-triangular S (a factor from choleskyLower), by substitution a
// row at a time; B is a vector or a matrix. Written out because Eigen's triangular solve with a matrix
// right-hand side takes its general blocked path (packing, level-3 kernels), which at these sizes costs
// more than the arithmetic around it.
template <class Lower, class Rhs>
void solveLowerInPlace(const Lower& s, Rhs& b) {
  for (int i = 0; i < int(s.rows()); ++i) {
    for (int k = 0; k < i; ++k) b.row(i) -= s(i, k) * b.row(k);
    b.row(i) /= s(i, i);
  }
}
template <class Lower, class Rhs>
void solveUpperInPlace(const Lower& s, Rhs& b) {
  for (int i = int(s.rows()) - 1; i >= 0; --i) {
    for (int k = i + 1; k < int(s.rows()); ++k) b.row(i) -= s(k, i) * b.row(k);
    b.row(i) /= s(i, i);
  }
}

// Whether every entry above the diagonal is exactly zero (a NaN there is not).
template <class Matrix>
bool isLowerTriangular(const Matrix& m) {
  for (int j = 1; j < int(m.cols()); ++j)
    for (int i = 0; i < j && i < int(m.rows()); ++i)
      if (!(m(i, j) == 0)) return false;
  return true;
}

// LU with partial pivoting, P M = L U, for a fixed-size square M up to 16 × 16: Eigen's unblocked
// algorithm, which its PartialPivLU runs at these sizes (the same pivots, the same bits unless the
// compiler fuses a(i, j) − a(i, k) a(k, j) in one and not the other), written out as plain loops. Eigen's class also
// compiles its blocked path for larger matrices, a triangular solve and a general product on dynamic blocks; a unit
// with the MJUKF's covariance of θ̂ spent about a second on it.
inline constexpr int kUnblockedLuBound = 16;  // Eigen's UnBlockedBound (LU/PartialPivLU.h)

template <class Matrix>
struct SmallLu {
  static constexpr int kSize = Matrix::RowsAtCompileTime;
  Matrix lu;                              // L below the diagonal (its unit diagonal implied), U on and above
  Eigen::Matrix<int, kSize, 1> rowSwaps;  // row k swapped with row rowSwaps(k), for k = 0, 1, … in turn
};

template <class Derived>
SmallLu<typename Derived::PlainObject> smallLu(const Eigen::MatrixBase<Derived>& m) {
  using Matrix = typename Derived::PlainObject;
  using Scalar = typename Matrix::Scalar;
  constexpr int n = Matrix::RowsAtCompileTime;
  static_assert(n != Eigen::Dynamic && n == Matrix::ColsAtCompileTime && n <= kUnblockedLuBound,
                "smallLu: a fixed-size square matrix up to kUnblockedLuBound");
  SmallLu<Matrix> f{m, {}};
  Matrix& a = f.lu;
  for (int k = 0; k < n; ++k) {
    // The first row of largest |a(i, k)|, i ≥ k (Eigen's maxCoeff: strictly larger replaces).
    int pivot = k;
    Scalar largest = std::abs(a(k, k));
    for (int i = k + 1; i < n; ++i)
      if (std::abs(a(i, k)) > largest) {
        largest = std::abs(a(i, k));
        pivot = i;
      }
    f.rowSwaps(k) = pivot;
    if (largest != Scalar(0)) {  // a zero column is left as it is, as Eigen does: U is then singular
      if (pivot != k) a.row(k).swap(a.row(pivot));
      for (int i = k + 1; i < n; ++i) a(i, k) /= a(k, k);
    }
    for (int j = k + 1; j < n; ++j)
      for (int i = k + 1; i < n; ++i) a(i, j) -= a(i, k) * a(k, j);
  }
  return f;
}

// B ← U⁻¹ L⁻¹ B for the unit lower L and upper U stored together in `lu`, by substitution a row at a time.
template <class Factors, class Rhs>
void substituteLuInPlace(const Factors& lu, Rhs& b) {
  const int n = int(lu.rows());
  for (int i = 1; i < n; ++i)
    for (int k = 0; k < i; ++k) b.row(i) -= lu(i, k) * b.row(k);
  for (int i = n - 1; i >= 0; --i) {
    for (int k = i + 1; k < n; ++k) b.row(i) -= lu(i, k) * b.row(k);
    b.row(i) /= lu(i, i);
  }
}

// B ← M⁻¹ B for the M factored by `lu`: SmallLu, or (above its bound) Eigen's PartialPivLU, whose own
// solve with a matrix right-hand side takes the blocked level-3 path, whose workspace fallback links
// malloc and free into a firmware image.
template <class Matrix, class Rhs>
void luSolveInPlace(const SmallLu<Matrix>& lu, Rhs& b) {
  for (int k = 0; k < SmallLu<Matrix>::kSize; ++k)
    if (lu.rowSwaps(k) != k) b.row(k).swap(b.row(lu.rowSwaps(k)));
  substituteLuInPlace(lu.lu, b);
}
template <class Lu, class Rhs>
void luSolveInPlace(const Lu& lu, Rhs& b) {
  b = lu.permutationP() * b;
  substituteLuInPlace(lu.matrixLU(), b);
}

// The LU factors of a fixed-size square M: SmallLu up to kUnblockedLuBound, Eigen's PartialPivLU above
// (its blocked algorithm; no matrix of the library's plants is that large).
template <class Derived>
auto partialPivotLu(const Eigen::MatrixBase<Derived>& m) {
  if constexpr (Derived::RowsAtCompileTime <= kUnblockedLuBound)
    return smallLu(m);
  else
    return Eigen::PartialPivLU<typename Derived::PlainObject>(m);
}

// ---- Covariances ----------------------------------------------------------------------------------------

// P ← (P + Pᵀ)/2 in place, a triangle at a time (no temporary, no aliasing). Halved before the sum,
// which gives the same bits as halving after it (subnormal entries aside) but cannot overflow for
// entries near the largest Scalar.
template <class Matrix>
void symmetrize(Matrix& p) {
  using Scalar = typename Matrix::Scalar;
  for (int c = 0; c < p.cols(); ++c)
    for (int r = c + 1; r < p.rows(); ++r) p(r, c) = p(c, r) = Scalar(0.5) * p(r, c) + Scalar(0.5) * p(c, r);
}

// ---- Fixed-size operands read through raw pointers ----------------------------------------------------------

// Whether M's columns lie in memory as runs of contiguous coefficients: column-major with unit inner
// stride, or a single row (which Eigen stores row-major: its columns are its coefficients). The kernels
// below read column k of such an M at data() + k · columnStride(m).
template <class M>
inline constexpr bool kContiguousColumns = (M::Flags & Eigen::DirectAccessBit) != 0 &&
                                           (M::RowsAtCompileTime == 1 || (!(M::Flags & Eigen::RowMajorBit) &&
                                                                          int(M::InnerStrideAtCompileTime) == 1));

template <class M>
Eigen::Index columnStride(const Eigen::MatrixBase<M>& m) {
  return M::RowsAtCompileTime == 1 ? m.derived().innerStride() : m.derived().outerStride();
}

// ---- A register-blocked product with a transpose (the general forms below) --------------------------------

enum class ProductPart { Full, Lower };       // every entry of out, or its lower triangle i ≥ j only
enum class ProductInto { Assign, Subtract };  // out(i, j) = Σ, or out(i, j) −= Σ

// out(i, j) = Σₖ a(i, k) b(j, k) (or −= it), i.e. A Bᵀ, for column-major A (R × K) and B (C × K) with
// contiguous columns; Part::Lower leaves the strictly upper triangle of out unread and unwritten. Blocks
// of out two packets of rows high and four columns wide are held in eight registers while k runs over
// the columns of A and B, every entry summed in order of k with one accumulator and Eigen's pmadd, as
// Eigen's GEMM kernel (gebp) sums it on x86-64: a full product or a subtraction there gives its bits.
// What it leaves out is GEMM's packing of both operands into panels and its dynamic-size dispatch, which
// at the filters' sizes cost more than they save: with the deviations' columns already contiguous, the
// packing only copies (`mjukf_kernel_bench`, L = 36, double, x86-64: covariance 8.4 → 6.9 µs, 36 × 18
// cross-covariance 6.5 → 6.1, P − U Uᵀ 2.2 → 1.9; bench/performance_notes.md).
template <ProductPart Part, ProductInto Into, class A, class B, class Out>
void productWithTranspose(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b, Eigen::MatrixBase<Out>& out) {
  using Scalar = typename Out::Scalar;
  using Packet = typename Eigen::internal::packet_traits<Scalar>::type;
  constexpr int kPacket = Eigen::internal::packet_traits<Scalar>::size;
  constexpr int kRows = 2 * kPacket, kCols = 4;
  constexpr int R = A::RowsAtCompileTime, C = B::RowsAtCompileTime, K = A::ColsAtCompileTime;
  static_assert(R != Eigen::Dynamic && C != Eigen::Dynamic && K == B::ColsAtCompileTime,
                "productWithTranspose: fixed sizes, A and B with the same number of columns");
  static_assert(kContiguousColumns<A> && kContiguousColumns<B>,
                "productWithTranspose: column-major operands held in memory, with contiguous columns");
  const Scalar* pa = a.derived().data();
  const Scalar* pb = b.derived().data();
  // a(i, k) = pa[i + k strideA] (i = 0 only for a single row), and so for b.
  const Eigen::Index strideA = columnStride(a);
  const Eigen::Index strideB = columnStride(b);
  const auto put = [&](int i, int j, Scalar sum) {
    if (Part == ProductPart::Lower && i < j) return;
    if constexpr (Into == ProductInto::Assign)
      out(i, j) = sum;
    else
      out(i, j) -= sum;
  };
  constexpr int blockedRows = R / kRows * kRows;
  for (int j0 = 0; j0 < C; j0 += kCols) {
    const int cols = std::min(kCols, C - j0);
    const int firstRow = Part == ProductPart::Lower ? j0 / kRows * kRows : 0;  // the block holding row j0
    for (int i0 = firstRow; i0 < blockedRows; i0 += kRows) {
      Packet sum[2][kCols];
      for (int c = 0; c < kCols; ++c) sum[0][c] = sum[1][c] = Eigen::internal::pset1<Packet>(Scalar(0));
      if (cols == kCols) {
        for (int k = 0; k < K; ++k) {
          const Packet top = Eigen::internal::ploadu<Packet>(pa + i0 + k * strideA);
          const Packet bottom = Eigen::internal::ploadu<Packet>(pa + i0 + kPacket + k * strideA);
          for (int c = 0; c < kCols; ++c) {
            const Packet bc = Eigen::internal::pset1<Packet>(pb[j0 + c + k * strideB]);
            sum[0][c] = Eigen::internal::pmadd(top, bc, sum[0][c]);
            sum[1][c] = Eigen::internal::pmadd(bottom, bc, sum[1][c]);
          }
        }
      } else {  // the last, narrower column block: one column at a time
        for (int c = 0; c < cols; ++c)
          for (int k = 0; k < K; ++k) {
            const Packet bc = Eigen::internal::pset1<Packet>(pb[j0 + c + k * strideB]);
            sum[0][c] = Eigen::internal::pmadd(Eigen::internal::ploadu<Packet>(pa + i0 + k * strideA), bc, sum[0][c]);
            sum[1][c] =
                Eigen::internal::pmadd(Eigen::internal::ploadu<Packet>(pa + i0 + kPacket + k * strideA), bc, sum[1][c]);
          }
      }
      Scalar tile[kRows];
      for (int c = 0; c < cols; ++c) {
        Eigen::internal::pstoreu(tile, sum[0][c]);
        Eigen::internal::pstoreu(tile + kPacket, sum[1][c]);
        for (int r = 0; r < kRows; ++r) put(i0 + r, j0 + c, tile[r]);
      }
    }
    // The rows below the last full block: one packet of them if there are enough, then one row at a
    // time, each with the block's columns summed side by side (independent sums, not one long chain).
    // i ≥ blockedRows: a packet of rows fits only if R − blockedRows ≥ kPacket. Said at compile time, this
    // also keeps GCC from warning of out-of-range rows in a branch it cannot prove dead.
    int i = std::max(blockedRows, firstRow);
    if constexpr (kPacket > 1 && R - blockedRows >= kPacket) {
      if (R - i >= kPacket) {
        Packet sum[kCols];
        for (int c = 0; c < kCols; ++c) sum[c] = Eigen::internal::pset1<Packet>(Scalar(0));
        for (int k = 0; k < K; ++k) {
          const Packet rows = Eigen::internal::ploadu<Packet>(pa + i + k * strideA);
          for (int c = 0; c < cols; ++c)
            sum[c] = Eigen::internal::pmadd(rows, Eigen::internal::pset1<Packet>(pb[j0 + c + k * strideB]), sum[c]);
        }
        Scalar tile[kPacket];
        for (int c = 0; c < cols; ++c) {
          Eigen::internal::pstoreu(tile, sum[c]);
          for (int r = 0; r < kPacket; ++r) put(i + r, j0 + c, tile[r]);
        }
        i += kPacket;
      }
    }
    for (; i < R; ++i) {
      Scalar sum[kCols] = {};
      for (int k = 0; k < K; ++k)
        for (int c = 0; c < cols; ++c) sum[c] += pa[i + k * strideA] * pb[j0 + c + k * strideB];
      for (int c = 0; c < cols; ++c) put(i, j0 + c, sum[c]);
    }
  }
}

// ---- Coefficient-wise maps of point sets --------------------------------------------------------------------

// out(i, k) = op(a(i, k), i, k) for column-major A and Out of the same fixed size held in memory, by
// packets through raw pointers (op takes a packet of rows i … i + P − 1, or one coefficient, and is
// written with Eigen's packet functions, which take a scalar as a packet of one). Eigen's own assignment
// loop for such a map, once the matrix is too large to unroll, reloads its operands' addresses after
// every packet it stores (a packet store may alias anything), and it forms colwise() − v without packets
// at all (docs/performance.md, "Issue 21: the deviations and the weighted deviations through raw
// pointers"). The same operations on the same values: the same bits.
template <class A, class Out, class Op>
void mapColumns(const Eigen::MatrixBase<A>& a, Eigen::MatrixBase<Out>& out, Op op) {
  using Scalar = typename Out::Scalar;
  using Packet = typename Eigen::internal::packet_traits<Scalar>::type;
  constexpr int kPacket = Eigen::internal::packet_traits<Scalar>::size;
  constexpr int R = A::RowsAtCompileTime, K = A::ColsAtCompileTime;
  static_assert(R != Eigen::Dynamic && K != Eigen::Dynamic && R == Out::RowsAtCompileTime &&
                    K == Out::ColsAtCompileTime && std::is_same_v<typename A::Scalar, Scalar>,
                "mapColumns: fixed sizes and one scalar type, A and out alike");
  static_assert(kContiguousColumns<A> && kContiguousColumns<Out>,
                "mapColumns: column-major operands held in memory, with contiguous columns");
  const Scalar* from = a.derived().data();
  Scalar* to = out.derived().data();
  const Eigen::Index strideA = columnStride(a);
  const Eigen::Index strideOut = columnStride(out);
  constexpr int packed = R / kPacket * kPacket;
  for (int k = 0; k < K; ++k, from += strideA, to += strideOut) {
    int i = 0;
    for (; i < packed; i += kPacket)
      Eigen::internal::pstoreu(to + i, op(Eigen::internal::ploadu<Packet>(from + i), i, k));
    for (; i < R; ++i) to[i] = op(from[i], i, k);
  }
}

// Whether Eigen has no vector unit for Scalar (packets of one coefficient, as on a Cortex-M4F). There its
// assignment loops store scalars, which cannot alias the expression's addresses, and unroll the rows of
// the filters' sizes, while mapColumns's loops are not unrolled at -O2 and took more instructions
// (docs/embedded.md, "The deviations by packets, on the target"): weightColumns and deviationsFrom keep
// Eigen's expressions there.
template <class Scalar>
inline constexpr bool kScalarPackets = Eigen::internal::packet_traits<Scalar>::size == 1;
// There, for L = Count / 2 from kLazyWeightingFrom to kLazyWeightingTo, the covariance kernel forms d W
// in each column's product instead of holding it (weightedCovarianceLowerLazilyWeighted; docs/embedded.md,
// "The covariance kernel by size on the target"): below, forming d W again costs more than the stack it
// saves. Above, the general kernels take over from L = 9; were their sizes moved, L = 9–13 would still
// be left out: there Eigen unrolls the held form's sums, which it adds pairwise, and not the lazy form's,
// which it adds in order, and the two would round apart. Which sums Eigen unrolls depends on its
// unrolling limit, so the range holds for its default only (another EIGEN_UNROLLING_LIMIT keeps the held
// form).
inline constexpr int kLazyWeightingFrom = 6, kLazyWeightingTo = 8;
template <class Scalar, int L>
constexpr bool lazyWeighting() {
  constexpr bool eigensDefaultUnrolling = EIGEN_UNROLLING_LIMIT == 110;
  return kScalarPackets<Scalar> && eigensDefaultUnrolling && kLazyWeightingFrom <= L && L <= kLazyWeightingTo;
}

// out = a W, i.e. out(:, k) = Wₖ a(:, k): each product as Eigen's a * weights.asDiagonal() forms it.
template <class A, class Weights, class Out>
void weightColumns(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<Weights>& weights,
                   Eigen::MatrixBase<Out>& out) {
  if constexpr (kScalarPackets<typename Out::Scalar>) {
    out.noalias() = a * weights.asDiagonal();
  } else {
    static_assert(int(Weights::SizeAtCompileTime) == int(Out::ColsAtCompileTime),
                  "weightColumns: one weight per column");
    const typename Weights::PlainObject& plain = weights.derived();  // contiguous (no copy when it is already)
    const auto* w = plain.data();
    mapColumns(a, out,
               [w](auto x, int, int k) { return Eigen::internal::pmul(x, Eigen::internal::pset1<decltype(x)>(w[k])); });
  }
}

// out(:, k) = points(:, k) − center: the deviations of a point set, as Eigen's points.colwise() − center
// forms them.
template <class Points, class Center, class Out>
void deviationsFrom(const Eigen::MatrixBase<Points>& points, const Eigen::MatrixBase<Center>& center,
                    Eigen::MatrixBase<Out>& out) {
  if constexpr (kScalarPackets<typename Out::Scalar>) {
    out.noalias() = points.colwise() - center;
  } else {
    static_assert(int(Center::SizeAtCompileTime) == int(Out::RowsAtCompileTime),
                  "deviationsFrom: a centre of the points' rows");
    const typename Center::PlainObject& plain = center.derived();  // contiguous (no copy when it is already)
    const auto* c = plain.data();
    mapColumns(points, out, [c](auto x, int i, int) {
      return Eigen::internal::psub(x, Eigen::internal::ploadu<decltype(x)>(c + i));
    });
  }
}

// ---- Weighted moments of a point set (the unscented transform, docs/algorithms.md §2–3) ---------------------

// mean = Σ Wmᵢ Xᵢ
template <class Points, class Weights, class Mean>
void weightedMean(const Eigen::MatrixBase<Points>& points, const Eigen::MatrixBase<Weights>& weights,
                  Eigen::MatrixBase<Mean>& mean) {
  mean.noalias() = points * weights;
}

// out = Σ Wcᵢ aᵢ bᵢᵀ of the deviations aᵢ, bᵢ (columns): the covariance when a = b, otherwise the
// cross-covariance. Small point sets: a coefficient-wise product (lazyProduct): left to choose, Eigen
// takes its general GEMM kernel once rows + columns + depth exceed 20 (JUKF on the robot: 6 + 6 + 13),
// and packing the operands then costs more than the whole rest of the step. Large ones (L = Count / 2
// from crossProduct on): (a W) bᵀ by register blocks (productWithTranspose), the sums of Eigen's general
// product without its packing; a W is formed first, as Eigen's product forms it, and b is read in place
// when it is a matrix (an expression is evaluated once).
template <class DevA, class DevB, class Weights, class Out>
MJUKF_FLATTEN void weightedOuterSumCoefficientwise(const Eigen::MatrixBase<DevA>& a, const Eigen::MatrixBase<DevB>& b,
                                                   const Eigen::MatrixBase<Weights>& weights,
                                                   Eigen::MatrixBase<Out>& out) {
  out.noalias() = (a * weights.asDiagonal()).lazyProduct(b.transpose());
}
// (a W) bᵀ into out (Part: all of it, or its lower triangle), by productWithTranspose.
template <ProductPart Part, class DevA, class DevB, class Weights, class Out>
void weightedProductWithTranspose(const Eigen::MatrixBase<DevA>& a, const Eigen::MatrixBase<DevB>& b,
                                  const Eigen::MatrixBase<Weights>& weights, Eigen::MatrixBase<Out>& out) {
  typename DevA::PlainObject weighted;
  weightColumns(a.derived().eval(), weights, weighted);
  const typename DevB::PlainObject& right = b.derived();  // no copy when b is a matrix already
  productWithTranspose<Part, ProductInto::Assign>(weighted, right, out);
}
template <class DevA, class DevB, class Weights, class Out>
void weightedOuterSumProduct(const Eigen::MatrixBase<DevA>& a, const Eigen::MatrixBase<DevB>& b,
                             const Eigen::MatrixBase<Weights>& weights, Eigen::MatrixBase<Out>& out) {
  weightedProductWithTranspose<ProductPart::Full>(a, b, weights, out);
}
template <class DevA, class DevB, class Weights, class Out>
void weightedOuterSum(const Eigen::MatrixBase<DevA>& a, const Eigen::MatrixBase<DevB>& b,
                      const Eigen::MatrixBase<Weights>& weights, Eigen::MatrixBase<Out>& out) {
  if constexpr (atLeast<DevA::ColsAtCompileTime / 2>(generalKernelsFrom<typename Out::Scalar>.crossProduct))
    weightedOuterSumProduct(a, b, weights, out);
  else
    weightedOuterSumCoefficientwise(a, b, weights, out);
}

// The strictly upper triangle of a square m ← its lower triangle, transposed.
template <class Matrix>
void mirrorLowerTriangle(Eigen::MatrixBase<Matrix>& m) {
  for (int c = 1; c < int(m.cols()); ++c)
    for (int r = 0; r < c; ++r) m(r, c) = m(c, r);
}

// Calls f(c, rows) for each column c = 0 … N − 1 of a lower triangle, rows = N − c its rows from the
// diagonal down. Up to N = 12, rows is a compile-time size (Eigen::fix<N − c>), so that every block
// has a fixed size and the compiler unrolls it; above, a plain int, so that the code and its compile
// time do not grow as N² (the tests and the kernel benchmark instantiate these forms up to N = 36).
template <int N, class F>
void forEachLowerColumn(F&& f) {
  if constexpr (N <= 12) {
    forEachIndex<N>([&](auto column) {
      constexpr int c = decltype(column)::value;
      f(c, Eigen::fix<N - c>);
      return true;
    });
  } else {
    for (int c = 0; c < N; ++c) f(c, N - c);
  }
}

// The lower triangle of out ← Σ Wcᵢ dᵢ dᵢᵀ, a covariance; the strictly upper triangle is for the caller
// to mirror (a symmetric result needs one triangle, about half the products of the full sum). Three forms:
//  - small point sets, coefficient-wise: column c's rows c … L − 1 as a coefficient-wise product of the
//    weighted deviations' rows with row c: the lower triangle of the full coefficient-wise sum
//    (weightedOuterSumCoefficientwise) up to the order of its sums, which Eigen's vectorisation chooses
//    (that full sum is not exactly symmetric either: (Wₖ aᵢₖ) aⱼₖ and (Wₖ aⱼₖ) aᵢₖ round apart);
//  - from covarianceProduct, the lower triangle of (d W) dᵀ by register blocks (productWithTranspose):
//    each entry the sum Eigen's general product forms for it, without its packing. (Before it, the
//    general product of both triangles up to covarianceTriangle and Eigen's product into one triangle
//    from there, which packed too; one matrix-vector product per column had taken 7–23 % fewer
//    instructions than the latter at L = 20, 24, 28 and 36, but 2 % (double) and 14 % (float) more at
//    32, the chain's n = 32: not taken.)
template <class Dev, class Weights, class Out>
MJUKF_FLATTEN void weightedCovarianceLowerCoefficientwise(const Eigen::MatrixBase<Dev>& d,
                                                          const Eigen::MatrixBase<Weights>& weights,
                                                          Eigen::MatrixBase<Out>& out) {
  constexpr int N = Dev::RowsAtCompileTime;
  const Eigen::Matrix<typename Out::Scalar, N, Dev::ColsAtCompileTime> weighted = d * weights.asDiagonal();
  forEachLowerColumn<N>([&](auto c, auto rows) {
    out.col(c).tail(rows).noalias() = weighted.bottomRows(rows).lazyProduct(d.row(c).transpose());
  });
}
// The same sums with d W formed again in each column's product rather than held: without the N × (2L + 1)
// temporary on the stack, for more multiplications; the same products, added in the same order where Eigen
// unrolls both forms' sums or neither (kLazyWeightingTo).
template <class Dev, class Weights, class Out>
MJUKF_FLATTEN void weightedCovarianceLowerLazilyWeighted(const Eigen::MatrixBase<Dev>& d,
                                                         const Eigen::MatrixBase<Weights>& weights,
                                                         Eigen::MatrixBase<Out>& out) {
  forEachLowerColumn<Dev::RowsAtCompileTime>([&](auto c, auto rows) {
    out.col(c).tail(rows).noalias() = (d.bottomRows(rows) * weights.asDiagonal()).lazyProduct(d.row(c).transpose());
  });
}
template <class Dev, class Weights, class Out>
void weightedCovarianceLowerTriangle(const Eigen::MatrixBase<Dev>& d, const Eigen::MatrixBase<Weights>& weights,
                                     Eigen::MatrixBase<Out>& out) {
  weightedProductWithTranspose<ProductPart::Lower>(d, d, weights, out);
}
template <class Dev, class Weights, class Out>
void weightedCovarianceLower(const Eigen::MatrixBase<Dev>& d, const Eigen::MatrixBase<Weights>& weights,
                             Eigen::MatrixBase<Out>& out) {
  constexpr int L = Dev::ColsAtCompileTime / 2;
  if constexpr (atLeast<L>(generalKernelsFrom<typename Out::Scalar>.covarianceProduct))
    weightedCovarianceLowerTriangle(d, weights, out);
  else if constexpr (lazyWeighting<typename Out::Scalar, L>())
    weightedCovarianceLowerLazilyWeighted(d, weights, out);
  else
    weightedCovarianceLowerCoefficientwise(d, weights, out);
}
// out = Σ Wcᵢ dᵢ dᵢᵀ, exactly symmetric: weightedCovarianceLower, mirrored.
template <class Dev, class Weights, class Out>
void weightedCovariance(const Eigen::MatrixBase<Dev>& d, const Eigen::MatrixBase<Weights>& weights,
                        Eigen::MatrixBase<Out>& out) {
  weightedCovarianceLower(d, weights, out);
  mirrorLowerTriangle(out);
}

// P ← P − U Uᵀ (U = P_xy S⁻ᵀ, the measurement update's K P_yy Kᵀ), exactly symmetric when P is: the
// lower triangle is computed and mirrored. Small L: coefficient-wise, column c's rows c … L − 1 (a
// coefficient-wise product over both triangles is not symmetric: Eigen's vectorisation sums some
// coefficients in another order than their mirror images). Large L: the lower triangle of U Uᵀ by
// register blocks (productWithTranspose), the sums of Eigen's symmetric rank-k update without its
// packing.
template <class Cov, class Cols>
void subtractOuterCoefficientwise(Eigen::MatrixBase<Cov>& p, const Eigen::MatrixBase<Cols>& u) {
  forEachLowerColumn<Cov::RowsAtCompileTime>([&](auto c, auto rows) {
    p.col(c).tail(rows).noalias() -= u.bottomRows(rows).lazyProduct(u.row(c).transpose());
  });
  mirrorLowerTriangle(p);
}
template <class Cov, class Cols>
void subtractOuterRankUpdate(Eigen::MatrixBase<Cov>& p, const Eigen::MatrixBase<Cols>& u) {
  const typename Cols::PlainObject& columns = u.derived();  // no copy when u is a matrix already
  productWithTranspose<ProductPart::Lower, ProductInto::Subtract>(columns, columns, p);
  mirrorLowerTriangle(p);
}
template <class Cov, class Cols>
void subtractOuter(Eigen::MatrixBase<Cov>& p, const Eigen::MatrixBase<Cols>& u) {
  if constexpr (atLeast<Cov::RowsAtCompileTime>(generalKernelsFrom<typename Cov::Scalar>.subtractRankUpdate))
    subtractOuterRankUpdate(p, u);
  else
    subtractOuterCoefficientwise(p, u);
}

// C ← U = C S⁻ᵀ for a lower-triangular S, i.e. U Sᵀ = C solved a column at a time (the columns of U are
// contiguous). With C = P_xy and P_yy = S Sᵀ, U is the gain's factor: K = U S⁻¹ and K P_yy Kᵀ = U Uᵀ.
template <class Lower, class Cross>
void whitenColumns(const Lower& s, Cross& c) {
  for (int j = 0; j < int(s.rows()); ++j) {
    for (int k = 0; k < j; ++k) c.col(j) -= s(j, k) * c.col(k);
    c.col(j) /= s(j, j);
  }
}

// ---- The symmetric sigma-point draw (docs/algorithms.md §1) ------------------------------------------------

// points = [x̂ (when `center`),  x̂ + γ Sᵢ (i = 1 … L),  x̂ − γ Sᵢ (i = 1 … L)] for the columns Sᵢ of a lower
// factor S of the covariance (P = S Sᵀ; only its lower triangle is read): van der Merwe's scaled set
// (center, γ = √(L + λ)) and the cubature set (no center, γ = √L) alike. Columns of S, not rows: rows
// would be wrong for a correlated P.
template <bool Center, class Vector, class Factor, class Points, class Scalar>
void drawSymmetricPoints(const Vector& mean, const Factor& lowerFactor, Scalar gamma, Points& points) {
  constexpr int L = Vector::RowsAtCompileTime;
  constexpr int first = Center ? 1 : 0;
  for (int i = 0; i < L; ++i) {
    points.col(first + i) = mean;
    points.col(first + L + i) = mean;
    for (int r = i; r < L; ++r) {  // S is lower triangular: rows above the diagonal are zero.
      const Scalar offset = gamma * lowerFactor(r, i);
      points(r, first + i) += offset;
      points(r, first + L + i) -= offset;
    }
  }
  if constexpr (Center) points.col(0) = mean;
}

// ---- Square-root factors (the square-root form, docs/algorithms.md §10) ------------------------------------
//
// The kernels of the square-root form (van der Merwe & Wan, 2001), in which the lower Cholesky factor
// S of P is what a step propagates:
//  - lowerFactorOfGram / lowerFactorOfOuter: the triangular factor of AᵀA (of B Bᵀ) by Householder
//    QR of A (LQ of B), never forming the product: the SR-UKF's qr([√Wc (χᵢ − x̂) …, √Q]ᵀ);
//  - choleskyRankOneUpdate / choleskyRankUpdate: S Sᵀ ± v vᵀ (± U Uᵀ) refactored from S in O(N²) per
//    column: the SR-UKF's cholupdate by a point of negative weight and its measurement downdate by U;
//  - outerOfLower: P = S Sᵀ formed from a lower factor, exactly symmetric;
//  - psdSquareRoot: a G with G Gᵀ = Q for a semi-definite Q (once, at construction).
// Like choleskyLower: fixed sizes, no allocation, loops over a compile-time index (forEachIndex), and
// "returns false, output unspecified" when the result would not be numerically positive definite.
//
// The margin. choleskyLower accepts a pivot dⱼ = s_jj² of P only above N ε P_jj, the size of its own
// rounding error. These kernels compute S, not P, and apply the same rule to what they compute: with
// rⱼ = ‖row j of S‖ (= √P_jj, the scale of everything they do in row j), they accept s_jj > 4N ε rⱼ.
//  - A Householder reflection is orthogonal, so its rounding errors in row j of S are of size ε rⱼ,
//    not ε rⱼ² (Higham, Accuracy and Stability of Numerical Algorithms, Thm 19.4: the computed R is
//    the exact R of A + ΔA with ‖Δaⱼ‖ ≤ γ̃ ‖aⱼ‖, column by column). Measured on exactly and nearly
//    rank-deficient A (a column a multiple or a combination of the others; 2·10⁴ random A for each of
//    2×2, 6×2, 4×4, 12×4, 6×6, 18×6, 13×13, 39×13, double and float), the computed s_jj of the
//    deficient column is at most 4.5 ε rⱼ, 2 ε rⱼ at the 99th percentile, whatever the shape. N ε
//    alone (choleskyLower's factor) passes 1.5 % of the 6 × 2 ones; 4N ε keeps choleskyLower's
//    growth with N (the worst-case bound grows with the number of reflections a column goes through)
//    and is ≥ 1.7× the largest error seen at every N ≥ 2.
//  - In terms of P this is s_jj² > 16 N² ε² P_jj, far below choleskyLower's N ε P_jj: the square-root
//    form represents factors of covariances that have no numerical Cholesky factor as P, which is its
//    purpose. A factor accepted here can have an S Sᵀ that choleskyLower refuses.
//  - The rank-one kernels hold their result to the same margin (so that a downdate by zero accepts
//    every S the Gram factor produces), and a downdate also to 1 − ‖S⁻¹v‖² > 4N ε (see there).

// 4N ε: the relative size, in a row of S, below which a pivot is rounding (see the top of this section).
template <class Scalar, int N>
constexpr Scalar squareRootMargin() {
  return Scalar(4 * N) * std::numeric_limits<Scalar>::epsilon();
}

template <class T>
struct NonDeducedType {
  using type = T;
};
// A parameter type that takes no part in deduction: `sign` converts from -1 for a float factor.
template <class T>
using NonDeduced = typename NonDeducedType<T>::type;

// One Householder reflection of the triangularisations below (the LAPACK one, dlarfg without its
// rescaling): H = I − τ u uᵀ with u = (1, x₁/v₀, …), v₀ = α + sign(α) σ (no cancellation),
// τ = (σ + |α|)/σ ∈ [1, 2], which maps x = (α, x₁, …) to −sign(α) σ e₁; `sign` is −sign(α) (the sign
// of R(j, j), moved into column j of S) and `scale` = 1/v₀. Refused (false) when σ² is not above the
// margin of row j of S: ‖row j‖² = Σₖ<ⱼ s_jk² + σ², the reflections so far having kept its norm. NaN
// and an overflowed σ² fail too.
template <class Scalar>
struct Reflection {
  Scalar sigma, tau, sign, scale;
};
template <int j, int m, class Segment, class Scalar, int N>
bool reflectionOf(const Segment& x, const Eigen::Matrix<Scalar, N, N>& s, Reflection<Scalar>& h) {
  constexpr Scalar margin2 = squareRootMargin<Scalar, N>() * squareRootMargin<Scalar, N>();  // on squares
  const Scalar alpha = x(0);
  Scalar sigma2 = alpha * alpha;
  if constexpr (m > 1) sigma2 += x.template tail<m - 1>().squaredNorm();
  Scalar above2 = Scalar(0);
  if constexpr (j > 0) above2 = s.row(j).template head<j>().squaredNorm();
  if (!(sigma2 > margin2 * (above2 + sigma2))) return false;
  h.sigma = std::sqrt(sigma2);
  const Scalar magnitude = std::abs(alpha) + h.sigma;  // |v₀|
  h.tau = magnitude / h.sigma;
  h.sign = alpha < Scalar(0) ? Scalar(1) : Scalar(-1);
  h.scale = -h.sign / magnitude;
  return true;
}

// S lower triangular with S Sᵀ = Aᵀ A, by Householder QR of A in place (A = Q R, S = Rᵀ with the signs
// of its columns chosen so that diag(S) > 0; the strictly upper part of S is set to zero). A is scratch
// afterwards. Returns false, S then unspecified, when A has a NaN or Inf, or when AᵀA is not
// numerically positive definite: a diagonal s_jj not above 4N ε ‖aⱼ‖ (aⱼ column j of A; see the
// margin above), which includes overflow of ‖aⱼ‖². The range is that of P = AᵀA: entries whose squares
// underflow or overflow fail, as they would in P. In the SR-UKF, A is the (2L + L) × L matrix whose rows
// are the √Wcᵢ (χᵢ − x̂), i ≥ 1, and the rows of Gᵀ, Q = G Gᵀ.
//
// Each reflection (reflectionOf) is applied to each later column by one fixed-length dot product and
// one axpy of contiguous (column-major) coefficients.
template <class Scalar, int Rows, int N>
bool lowerFactorOfGram(Eigen::Matrix<Scalar, Rows, N>& a, Eigen::Matrix<Scalar, N, N>& s) {
  static_assert(N >= 1 && Rows >= N, "the Gram factor needs at least as many rows as columns");
  if (!allFinite(a)) return false;
  return forEachIndex<N>([&](auto jIndex) {
    constexpr int j = jIndex.value;
    constexpr int m = Rows - j;  // coefficients of column j from the diagonal down
    auto x = a.col(j).template segment<m>(j);
    Reflection<Scalar> h;
    if (!reflectionOf<j, m>(x, s, h)) return false;
    const Scalar sigma = h.sigma, tau = h.tau, sign = h.sign, scale = h.scale;
    s(j, j) = sigma;
    for (int k = j + 1; k < N; ++k) {
      auto y = a.col(k).template segment<m>(j);
      // w = τ uᵀy with the dot product of the unscaled x, which does not wait for σ's root and division.
      Scalar w = y(0);
      if constexpr (m > 1) w += scale * x.template tail<m - 1>().dot(y.template tail<m - 1>());
      w *= tau;
      s(k, j) = sign * (y(0) - w);  // R(j, k), signed as S's column j
      if constexpr (m > 1) y.template tail<m - 1>() -= (w * scale) * x.template tail<m - 1>();
    }
    forEachIndex<j>([&](auto i) { return s(i.value, j) = Scalar(0), true; });
    return true;
  });
}

// The same factor in the other layout: S lower triangular with S Sᵀ = B Bᵀ = Σ bᵢ bᵢᵀ, the bᵢ the
// columns of B (N × Cols): the LQ factorisation B = L Q by reflections from the right, with B scratch
// afterwards. This is the layout in which the engine has the deviations (L × Count, a column per
// point), so the caller writes [√Wc (χᵢ − x̂) …, G] as columns without a transpose. Same contract and
// margin as lowerFactorOfGram, with ‖row j of B‖ for ‖aⱼ‖. Each reflection is applied to all later rows
// at once: w = B₍ⱼ₊₁..,ⱼ..₎ u as a sum of contiguous column segments, then a rank-one update.
template <class Scalar, int N, int Cols>
bool lowerFactorOfOuter(Eigen::Matrix<Scalar, N, Cols>& b, Eigen::Matrix<Scalar, N, N>& s) {
  static_assert(N >= 1 && Cols >= N, "the factor of B Bᵀ needs at least as many columns as rows");
  if (!allFinite(b)) return false;
  return forEachIndex<N>([&](auto jIndex) {
    constexpr int j = jIndex.value;
    constexpr int m = Cols - j;       // coefficients of row j from the diagonal right
    constexpr int below = N - j - 1;  // rows the reflection is applied to
    auto x = b.row(j).template segment<m>(j);
    Reflection<Scalar> h;
    if (!reflectionOf<j, m>(x, s, h)) return false;
    const Scalar sigma = h.sigma, tau = h.tau, sign = h.sign, scale = h.scale;
    s(j, j) = sigma;
    forEachIndex<j>([&](auto i) { return s(i.value, j) = Scalar(0), true; });
    if constexpr (below > 0) {
      // w = τ B u, its sum over the unscaled x first, which does not wait for σ's root and division.
      Eigen::Matrix<Scalar, below, 1> sum = Eigen::Matrix<Scalar, below, 1>::Zero();
      for (int c = j + 1; c < Cols; ++c) sum += b(j, c) * b.col(c).template segment<below>(j + 1);
      const Eigen::Matrix<Scalar, below, 1> w = tau * (b.col(j).template segment<below>(j + 1) + scale * sum);
      s.col(j).template segment<below>(j + 1) = sign * (b.col(j).template segment<below>(j + 1) - w);
      const Eigen::Matrix<Scalar, below, 1> ws = scale * w;
      for (int c = j + 1; c < Cols; ++c) b.col(c).template segment<below>(j + 1) -= b(j, c) * ws;
    }
    return true;
  });
}

namespace squareRootImpl {

// S ← the factor of S Sᵀ ± X Xᵀ, consuming X (N × M). Column k of S is rotated against every column of
// X in turn, then column k + 1: the same operations on the same values as applying the columns of X
// one after the other (step k of column i needs only step k − 1 of column i, through xᵢ, and step k
// of column i − 1, through column k of S), hence bit for bit the same S, but with M chains of
// dependent roots and divisions in flight instead of one: the critical path is N + M steps, not N M.
// Checked: each rotation's pivot (downdate: πᵢ, which keeps every pivot positive), and the pivot of
// the new S once row k is final; s'_kj (j < k) enter through the row norm there, so a NaN or Inf
// anywhere (in S, in X, or from an overflow) fails at the latest at its row.
template <bool Downdate, class Scalar, int N, int M>
bool rankUpdate(Eigen::Matrix<Scalar, N, N>& s, Eigen::Matrix<Scalar, N, M>& x) {
  constexpr Scalar margin = squareRootMargin<Scalar, N>();
  Scalar remaining[M];  // πᵢ = 1 − Σⱼ≤ₖ aᵢⱼ², aᵢ = Sᵢ₋₁⁻¹ xᵢ (downdate)
  for (int i = 0; i < M; ++i) remaining[i] = Scalar(1);
  return forEachIndex<N>([&](auto kIndex) {
    constexpr int k = kIndex.value;
    constexpr int below = N - k - 1;
    auto column = s.col(k).template segment<below>(k + 1);
    for (int i = 0; i < M; ++i) {
      const Scalar skk = s(k, k), xk = x(k, i);
      auto rest = x.col(i).template segment<below>(k + 1);
      if constexpr (Downdate) {
        const Scalar pivot = (skk - xk) * (skk + xk);  // r² = s_kk² − x_k², without cancellation
        const Scalar inverseDiagonal = Scalar(1) / skk;
        remaining[i] *= pivot * inverseDiagonal * inverseDiagonal;  // c² = r² / s_kk²
        if (!(remaining[i] > margin)) return false;                 // NaN fails too
        // r and 1/r = r · (1/r²): the root and the division side by side, not one after the other.
        const Scalar r = std::sqrt(pivot);
        const Scalar inverseR = r * (Scalar(1) / pivot);
        s(k, k) = r;
        if constexpr (below > 0) {
          const Scalar rho = xk * inverseDiagonal;
          column = (skk * inverseR) * (column - rho * rest);   // (s − ρ x) / c
          rest = (r * inverseDiagonal) * rest - rho * column;  // c x − ρ s with the NEW s: the mixed form
        }
      } else {
        const Scalar pivot = skk * skk + xk * xk;
        const Scalar r = std::sqrt(pivot);
        const Scalar inverseR = r * (Scalar(1) / pivot);  // NaN when r = 0: fails at the row check
        s(k, k) = r;
        if constexpr (below > 0) {
          const Scalar c = skk * inverseR, t = xk * inverseR;
          const Eigen::Matrix<Scalar, below, 1> old = column;
          column = c * column + t * rest;
          rest = c * rest - t * old;
        }
      }
    }
    Scalar above2 = Scalar(0);  // Σⱼ<ₖ s'_kj², final
    if constexpr (k > 0) above2 = s.row(k).template head<k>().squaredNorm();
    const Scalar pivot = s(k, k) * s(k, k);
    return pivot > margin * margin * (above2 + pivot);  // the Gram factor's margin; NaN fails
  });
}

}  // namespace squareRootImpl

// S ← the lower Cholesky factor of S Sᵀ + v vᵀ (sign > 0, an update) or of S Sᵀ − v vᵀ (sign < 0, a
// downdate; 0 counts as an update). Only the sign of `sign` is read: for a weight w, pass √|w| v and w.
// S must be lower triangular with a positive diagonal (as choleskyLower and the Gram factor leave
// it); its strictly upper part is neither read nor written. v is copied. Returns false, S then
// unspecified, when
//  - the new S fails the Gram factor's margin: a pivot s'_kk not above 4N ε ‖row k of S'‖ (an update
//    fails only when S itself did and v does not fill that direction; a downdate by zero accepts
//    every S the Gram factor accepts);
//  - (downdate) S Sᵀ − v vᵀ is not numerically positive definite: 1 − ‖S⁻¹v‖² not above 4N ε. With
//    a = S⁻¹v, S Sᵀ − v vᵀ = S (I − a aᵀ) Sᵀ, whose definiteness is that of 1 − ‖a‖², whatever the
//    scale or conditioning of S; it is LINPACK dchdd's test (there with no margin), computed here as
//    the product of the rotations' c_k² = 1 − ρ_k². The downdate must leave more than 4N ε of P in
//    every direction, in P's own metric: the covariance form's P − v vᵀ, formed with rounding errors
//    of ε P_kk, then factored with choleskyLower's margin relative to its own (smaller) diagonal, has
//    no such test. The rounding error of 1 − ‖a‖² grows with the condition of S (about κ(S) ε,
//    measured): near the boundary a badly conditioned S is accepted or refused by rounding;
//  - anything is not finite.
//
// Column k is rotated against x (x = v at first), with r the new pivot:
//  - update: a Givens rotation (LINPACK dchud), r = √(s_kk² + x_k²), c = s_kk / r, t = x_k / r;
//    s_ik ← c s_ik + t x_i and x_i ← c x_i − t s_ik (old s_ik) for i > k;
//  - downdate: a hyperbolic rotation in the mixed form of Bojanczyk, Brent, Van Dooren & de Hoog
//    (SIAM J. Sci. Stat. Comput. 8, 1987), which is stable where the plain hyperbolic rotation is not:
//    r² = (s_kk − x_k)(s_kk + x_k), ρ = x_k / s_kk, c = r / s_kk; s_ik ← (s_ik − ρ x_i) / c first,
//    then x_i ← c x_i − ρ s_ik with the NEW s_ik.
template <class Scalar, int N, class Vec>
bool choleskyRankOneUpdate(Eigen::Matrix<Scalar, N, N>& s, const Eigen::MatrixBase<Vec>& v, NonDeduced<Scalar> sign) {
  static_assert(Vec::SizeAtCompileTime == N, "v must have the size of S");
  Eigen::Matrix<Scalar, N, 1> x = v;
  return sign < Scalar(0) ? squareRootImpl::rankUpdate<true>(s, x) : squareRootImpl::rankUpdate<false>(s, x);
}

// S ← the lower Cholesky factor of S Sᵀ + sign·U Uᵀ, U N × M (M fixed at compile time): the result of
// the rank-one kernel on each column of U in turn, bit for bit, computed with the columns interleaved
// (squareRootImpl::rankUpdate). For a downdate every intermediate S Sᵀ − Σ uᵢuᵢᵀ lies above the final
// one, so the order cannot make a positive definite result fail. Same contract: the new S must pass
// the Gram factor's margin, and (downdate) each column uᵢ must keep 1 − ‖Sᵢ₋₁⁻¹uᵢ‖² above 4N ε, Sᵢ₋₁
// the factor it is applied to. The SR-UKF's measurement update is the downdate by U = K S_y.
template <class Scalar, int N, class Cols>
bool choleskyRankUpdate(Eigen::Matrix<Scalar, N, N>& s, const Eigen::MatrixBase<Cols>& u, NonDeduced<Scalar> sign) {
  static_assert(Cols::RowsAtCompileTime == N, "U must have as many rows as S");
  static_assert(Cols::ColsAtCompileTime != Eigen::Dynamic, "U must have a fixed number of columns");
  Eigen::Matrix<Scalar, N, Cols::ColsAtCompileTime> x = u;
  return sign < Scalar(0) ? squareRootImpl::rankUpdate<true>(s, x) : squareRootImpl::rankUpdate<false>(s, x);
}

// P = S Sᵀ of a lower-triangular S (only its lower triangle is read): each coefficient once, as the
// dot product of two rows of S over the columns they share, and mirrored, so that P is exactly
// symmetric. The square-root form's committed covariance and its P_yy.
template <class Scalar, int N>
void outerOfLower(const Eigen::Matrix<Scalar, N, N>& s, Eigen::Matrix<Scalar, N, N>& p) {
  forEachIndex<N>([&](auto iIndex) {
    constexpr int i = iIndex.value;
    forEachIndex<i + 1>([&](auto jIndex) {
      constexpr int j = jIndex.value;
      Scalar v = s(i, 0) * s(j, 0);
      forEachIndex<j>([&](auto k) { return v += s(i, k.value + 1) * s(j, k.value + 1), true; });
      p(i, j) = v;
      p(j, i) = v;
      return true;
    });
    return true;
  });
}

// C ← C S⁻¹ for a lower-triangular S, i.e. K S = C solved a column at a time from the last. With
// C = U = P_xy S⁻ᵀ (whitenColumns) and P_yy = S Sᵀ, K is the gain P_xy P_yy⁻¹ = U S⁻¹.
template <class Lower, class Cross>
void rightSolveLowerInPlace(const Lower& s, Cross& c) {
  for (int j = int(s.rows()) - 1; j >= 0; --j) {
    for (int k = j + 1; k < int(s.rows()); ++k) c.col(j) -= s(k, j) * c.col(k);
    c.col(j) /= s(j, j);
  }
}

// G with G Gᵀ = Q for a symmetric positive semi-definite Q (reading its lower triangle), singular or
// zero Q included, by Cholesky with diagonal pivoting (Higham, Accuracy and Stability of Numerical
// Algorithms, §10.3): at each step the largest remaining diagonal of the Schur complement is the pivot,
// and the factorisation stops when it falls to N ε max(Q_jj), what is left being rounding. G is the
// lower factor with its rows put back in Q's order (so not triangular; only G Gᵀ matters where it is
// used). A Q with a NaN or Inf gives a G of NaN. For construction time: O(N³), not on the per-step path.
template <class Scalar, int N>
Eigen::Matrix<Scalar, N, N> psdSquareRoot(const Eigen::Matrix<Scalar, N, N>& q) {
  using Matrix = Eigen::Matrix<Scalar, N, N>;
  Matrix w = Matrix::Zero();  // the Schur complement, both triangles, rows and columns in pivot order
  Scalar largest = Scalar(0);
  for (int j = 0; j < N; ++j) {
    for (int i = j; i < N; ++i) w(i, j) = w(j, i) = q(i, j);
    largest = std::max(largest, q(j, j));
  }
  if (!allFinite(w)) return Matrix::Constant(std::numeric_limits<Scalar>::quiet_NaN());
  const Scalar tolerance = Scalar(N) * std::numeric_limits<Scalar>::epsilon() * largest;
  int order[N];  // order[i]: the row of Q that row i of the factor belongs to
  for (int i = 0; i < N; ++i) order[i] = i;
  Matrix l = Matrix::Zero();
  for (int j = 0; j < N; ++j) {
    int p = j;
    for (int i = j + 1; i < N; ++i)
      if (w(i, i) > w(p, p)) p = i;
    if (!(w(p, p) > tolerance)) break;
    if (p != j) {  // the symmetric swap of j and p in W, and of the rows of the factor so far
      for (int k = 0; k < N; ++k) std::swap(w(j, k), w(p, k));
      for (int k = 0; k < N; ++k) std::swap(w(k, j), w(k, p));
      for (int k = 0; k < j; ++k) std::swap(l(j, k), l(p, k));
      std::swap(order[j], order[p]);
    }
    const Scalar root = std::sqrt(w(j, j));
    l(j, j) = root;
    for (int i = j + 1; i < N; ++i) l(i, j) = w(i, j) / root;
    for (int k = j + 1; k < N; ++k)
      for (int i = j + 1; i < N; ++i) w(i, k) -= l(i, j) * l(k, j);
  }
  Matrix g = Matrix::Zero();
  for (int i = 0; i < N; ++i) g.row(order[i]) = l.row(i);
  return g;
}

// ---- The positive semi-definite part of a symmetric matrix -------------------------------------------------

// A scaled by an even power of two, 4⁻ᵏ A with its largest entry in [1/4, 1), into `scaled`; returns k.
// Exact (no rounding unless entries fall below the smallest normal number), so a positive part computed
// on it and multiplied by 2ᵏ is the unscaled computation's bit for bit, but the squares of a finite A
// near the overflow threshold (a P_θ that has grown without bound) and its eigenvalues no longer
// overflow. The power is applied in two halves, so that a subnormal A does not need 2¹⁰⁷⁴.
template <class Scalar, int N>
int scaleToUnitRange(const Eigen::Matrix<Scalar, N, N>& a, Eigen::Matrix<Scalar, N, N>& scaled) {
  int exponent = 0;
  std::frexp(a.cwiseAbs().maxCoeff(), &exponent);  // largest = f 2^exponent, f ∈ [1/2, 1)
  exponent += exponent & 1;                        // even: √ of the scale is exact
  const Scalar half = std::ldexp(Scalar(1), -exponent / 2);
  scaled = a * half;
  scaled *= half;
  return exponent / 2;
}

// E with E Eᵀ = A⁺, the positive semi-definite part of the symmetric A (its eigenvalues below zero set to
// zero), by cyclic Jacobi rotations: A = V D Vᵀ, E = V √max(D, 0). Each sweep rotates every off-diagonal
// pair to zero; the loop stops when the off-diagonal mass is below ε² of A's (or after 32 sweeps, which no
// finite A has needed). Reads the whole of A (symmetric as given), scaled (scaleToUnitRange). Returns
// false, E then unspecified, when A is not finite.
template <class Scalar, int N>
bool positivePartFactorJacobi(const Eigen::Matrix<Scalar, N, N>& a, Eigen::Matrix<Scalar, N, N>& factor) {
  using Matrix = Eigen::Matrix<Scalar, N, N>;
  if (!allFinite(a)) return false;
  Matrix d;
  const int power = scaleToUnitRange(a, d);
  Matrix v = Matrix::Identity();
  const Scalar scale = d.squaredNorm();
  const Scalar epsilon = std::numeric_limits<Scalar>::epsilon();
  for (int sweep = 0; sweep < 32; ++sweep) {
    Scalar off = 0;
    for (int q = 1; q < N; ++q)
      for (int p = 0; p < q; ++p) off += d(p, q) * d(p, q);
    if (!(off > epsilon * epsilon * scale)) break;
    for (int q = 1; q < N; ++q)
      for (int p = 0; p < q; ++p) {
        Eigen::JacobiRotation<Scalar> rotation;
        if (!rotation.makeJacobi(d, p, q)) continue;  // already zero
        d.applyOnTheLeft(p, q, rotation.adjoint());
        d.applyOnTheRight(p, q, rotation);
        v.applyOnTheRight(p, q, rotation);
      }
  }
  const Scalar root = std::ldexp(Scalar(1), power);
  for (int j = 0; j < N; ++j) factor.col(j) = v.col(j) * (std::sqrt(std::max(d(j, j), Scalar(0))) * root);
  return allFinite(factor);
}

// The same by Eigen's SelfAdjointEigenSolver (Householder tridiagonalisation, then implicit QR on the
// tridiagonal), on A scaled as the rotations take it (the solver's own scaling, by the largest entry,
// is not exact and let eigenvalues near the largest finite number overflow). It reads the lower
// triangle of A. A solver that did not converge (no finite A has been seen to) falls back to the
// rotations.
template <class Scalar, int N>
bool positivePartFactorTridiagonal(const Eigen::Matrix<Scalar, N, N>& a, Eigen::Matrix<Scalar, N, N>& factor) {
  using Matrix = Eigen::Matrix<Scalar, N, N>;
  if (!allFinite(a)) return false;
  Matrix scaled;
  const Scalar root = std::ldexp(Scalar(1), scaleToUnitRange(a, scaled));
  const Eigen::SelfAdjointEigenSolver<Matrix> solver(scaled);
  if (solver.info() != Eigen::Success) return positivePartFactorJacobi(a, factor);
  for (int j = 0; j < N; ++j)
    factor.col(j) = solver.eigenvectors().col(j) * (std::sqrt(std::max(solver.eigenvalues()(j), Scalar(0))) * root);
  return allFinite(factor);
}

// The positive semi-definite part, E with E Eᵀ = A⁺, by the faster of the two for the size, chosen at
// compile time: the rotations up to N = 4, Eigen's tridiagonal solver from 5. Measured standalone
// (g++ -O3, a random indefinite A; double, float): N = 4 1.1, 1.0 µs by rotations against 1.3, 0.95 by
// the solver; N = 5 2.6, 1.8 against 1.9, 1.3; N = 8 9.6 against 4.2; N = 16 94 against 20; N = 32 420
// against 83 (the automatic MJUKF's step on a chain of 32 states spent three quarters of its time in the
// rotations). Both are backward stable and A → A⁺ is 1-Lipschitz, so the two agree to rounding
// (tests/detail/linear_algebra_test.cpp); every plant of the library has N ≤ 4, whose results are the
// rotations' as before. The solver allocates nothing at these fixed sizes (its Householder sequence is
// formed in place, tests/no_allocation_test.cpp), but its code holds a blocked path with dynamic-size
// temporaries that is compiled in, so a firmware image that must not link malloc defines
// MJUKF_POSITIVE_PART_BY_ROTATIONS for the rotations at every size (docs/embedded.md).
#ifdef MJUKF_POSITIVE_PART_BY_ROTATIONS
inline constexpr int kTridiagonalPositivePartFrom = std::numeric_limits<int>::max();
#else
inline constexpr int kTridiagonalPositivePartFrom = 5;
#endif

template <class Scalar, int N>
bool positivePartFactor(const Eigen::Matrix<Scalar, N, N>& a, Eigen::Matrix<Scalar, N, N>& factor) {
  if constexpr (N != Eigen::Dynamic && N >= kTridiagonalPositivePartFrom)
    return positivePartFactorTridiagonal(a, factor);
  else
    return positivePartFactorJacobi(a, factor);
}

}  // namespace mjukf::detail
