#pragma once

/// \file
/// The covariance form of a filter, its template argument after the sigma-point set: what a
/// step propagates to describe the estimate's spread, the covariance P itself (`FullCovariance`, the
/// default) or its lower triangular square root S, P = S Sᵀ (`SquareRootCovariance`).
/// docs/algorithms.md §10 derives the square-root form; docs/design.md says how to choose.

#include <type_traits>

namespace mjukf {

/// The covariance form of the paper and of every release before 0.2: a step forms P⁻ = Σ Wcᵢ ΔχᵢΔχᵢᵀ + Q
/// and P = P⁻ − K P_yy Kᵀ explicitly (one triangle, mirrored: exactly symmetric) and factors it (Cholesky) before
/// committing it, with the bounded repair of covariance_repair.hpp when rounding made it lose definiteness. The
/// cheapest form, and accurate while P stays well conditioned (κ(P) far below 1/ε).
struct FullCovariance {};

/// The square-root form (van der Merwe and Wan, 2001): the lower Cholesky factor S of P is what a step
/// propagates, obtained by Householder triangularisation of weighted deviations and factors of the
/// noises and by rank-one updates, never by subtracting covariances, so that the committed S Sᵀ is
/// positive semi-definite by construction. It holds where the full form loses definiteness to
/// rounding, chiefly in float with near-exact measurements (R ≪ P). A step costs more covariance
/// arithmetic (docs/performance.md), and `covariance()` is S Sᵀ, formed once per committed step so
/// that it can be returned by reference. The same statuses: a step whose factor cannot be obtained
/// falls back to the full form's P and its repair (docs/algorithms.md §10).
struct SquareRootCovariance {};

/// \cond INTERNAL
namespace detail {
/// True for the square-root form; a static_assert of the estimate refuses any other tag than the two.
template <class Form>
inline constexpr bool isSquareRootForm = std::is_same_v<Form, SquareRootCovariance>;
template <class Form>
inline constexpr bool isCovarianceForm =
    std::is_same_v<Form, FullCovariance> || std::is_same_v<Form, SquareRootCovariance>;
}  // namespace detail
/// \endcond

}  // namespace mjukf
