#pragma once

/// \file
/// Umbrella header: the whole public API of mjukf.

#include "mjukf/diagnostics.hpp"
#include "mjukf/dual_ukf.hpp"
#include "mjukf/filter_settings.hpp"
#include "mjukf/integrators/integrators.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/model.hpp"
#include "mjukf/models/coupled_tank.hpp"
#include "mjukf/models/flexible_joint.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/paper_experiments.hpp"
#include "mjukf/paper_schedule.hpp"
#include "mjukf/sigma_points.hpp"
#include "mjukf/status.hpp"
#include "mjukf/ukf.hpp"
#include "mjukf/unscented_transform.hpp"
