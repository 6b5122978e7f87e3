#pragma once

/// \file
/// Umbrella header: the whole core API of mjukf. The paper's experiments, schedule and RMSE are a
/// layer of their own, `mjukf/paper/paper.hpp`.

#include "mjukf/covariance_form.hpp"
#include "mjukf/diagnostics.hpp"
#include "mjukf/dual_ukf.hpp"
#include "mjukf/filter_settings.hpp"
#include "mjukf/integrators/integrators.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/model.hpp"
#include "mjukf/models/coupled_tank.hpp"
#include "mjukf/models/flexible_joint.hpp"
#include "mjukf/models/lorenz.hpp"
#include "mjukf/models/van_der_pol.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/result.hpp"
#include "mjukf/settings_error.hpp"
#include "mjukf/sigma_points.hpp"
#include "mjukf/simulation.hpp"
#include "mjukf/status.hpp"
#include "mjukf/ukf.hpp"
#include "mjukf/unscented_transform.hpp"
