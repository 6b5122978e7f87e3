#pragma once

/// \file
/// The check of γ and the BDF2-stage weights shared by the explicit TR-BDF2 variants, `ITrBdf2` and
/// `ExplicitTrBdf2` (docs/algorithms.md §6).

#include "mjukf/detail/validation.hpp"
#include "mjukf/settings_error.hpp"

/// \cond INTERNAL
namespace mjukf::detail {

// γ, the fraction of the step taken by the trapezoidal stage, in (0, 1).
template <class Scalar>
SettingsError validateStageFraction(const char* owner, Scalar gamma) {
  if (!(gamma > 0 && gamma < 1)) return invalid(owner, "gamma", "must lie in (0, 1)");
  return {};
}

// x_{k+1} = current · x_γ + previous · x_k + slope · h · f: the BDF2 stage of a γ that
// validateStageFraction accepted.
template <class Scalar>
struct Bdf2Weights {
  explicit Bdf2Weights(Scalar g)
      : gamma(g),
        current(Scalar(1) / (g * (Scalar(2) - g))),
        previous(-(Scalar(1) - g) * (Scalar(1) - g) / (g * (Scalar(2) - g))),
        slope((Scalar(1) - g) / (Scalar(2) - g)) {}

  Scalar gamma;
  Scalar current;   // 1 / (γ(2−γ))
  Scalar previous;  // −(1−γ)² / (γ(2−γ))
  Scalar slope;     // (1−γ) / (2−γ)
};

}  // namespace mjukf::detail
/// \endcond
