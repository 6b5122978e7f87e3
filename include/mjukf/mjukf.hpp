#pragma once

/// \file
/// Umbrella header: the whole core API of mjukf, the filters, their settings, the steppers and the
/// concepts they rest on. Not included: the example plants (`mjukf/models/<plant>.hpp`, each included
/// on its own), the SUNDIALS adapter (`mjukf/sundials/cvode.hpp`, which needs SUNDIALS), the CSV
/// reader of recorded data (`mjukf/io/csv_reader.hpp`, which needs iostreams and the heap) and the
/// host-side tools over a whole record (`mjukf/offline/`: run, smoother, log-likelihood).

#include "mjukf/covariance_form.hpp"
#include "mjukf/covariance_repair.hpp"
#include "mjukf/diagnostics.hpp"
#include "mjukf/dual_ukf.hpp"
#include "mjukf/filter_settings.hpp"
#include "mjukf/integrators/integrators.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/measurement_gating.hpp"
#include "mjukf/model.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/parameter_bounds.hpp"
#include "mjukf/parameter_sensitivity.hpp"
#include "mjukf/recovery.hpp"
#include "mjukf/result.hpp"
#include "mjukf/settings_error.hpp"
#include "mjukf/sigma_points.hpp"
#include "mjukf/simulation.hpp"
#include "mjukf/status.hpp"
#include "mjukf/ukf.hpp"
#include "mjukf/unscented_transform.hpp"
