#pragma once

/// \file
/// Umbrella header of the paper layer: the two experiments' settings, the schedule their runs follow
/// and the RMSE they are scored by. Not part of the core (`mjukf/mjukf.hpp`): a user's own plant needs
/// none of it.

#include "mjukf/paper/experiments.hpp"
#include "mjukf/paper/rmse.hpp"
#include "mjukf/paper/schedule.hpp"
