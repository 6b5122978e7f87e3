#pragma once

/// \file
/// Umbrella header of the paper layer: the two experiments' settings, the schedule their runs follow
/// and the RMSE they are scored by. It belongs to the example programs (examples/support/, not
/// installed), not to the library: a user's own plant needs none of it.

#include "paper/experiments.hpp"
#include "paper/rmse.hpp"
#include "paper/schedule.hpp"
