#pragma once

/// \file
/// Every allocation-free stepper of mjukf. The CVODE adapter is separate (mjukf/sundials/cvode.hpp)
/// because it needs SUNDIALS.
///
/// A stepper is a class with `Scalar`, `static constexpr int order`, `static constexpr int
/// evaluationsPerStep` (−1 when it varies) and `State step(f, t, x, h) const`, where `f(t, x)`
/// returns ẋ. docs/integrators.md compares their accuracy and cost on both plants.

#include "mjukf/integrators/explicit_tr_bdf2.hpp"
#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/integrators/tr_bdf2.hpp"
