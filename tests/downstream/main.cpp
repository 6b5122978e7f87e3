// Built against the installed package: the umbrella header, an installed plant, and one filter step
// of each kind with the settings written out (the paper's presets are not installed).
#include <cstdio>

#include <mjukf/mjukf.hpp>
#include <mjukf/models/coupled_tank.hpp>

int main() {
  using Tank = mjukf::models::CoupledTank<double>;
  const Tank::State x0 = Tank::State::Zero();
  const Tank::Param theta0 = Tank::Param::Constant(2.0);

  mjukf::JointUkfSettingsFor<Tank> jointSettings;
  jointSettings.initialCovariance.diagonal() << 0.5, 0.5, 0.1;
  jointSettings.processNoise.diagonal().setConstant(1e-5);
  jointSettings.measurementNoise.diagonal().setConstant(1e-7);
  mjukf::JointUkf<Tank> joint(Tank(), x0, theta0, jointSettings);

  mjukf::ModifiedJointUkfSettingsFor<Tank> modifiedSettings;
  modifiedSettings.initialCovariance.diagonal().setConstant(0.5);
  modifiedSettings.processNoise.diagonal().setConstant(1e-5);
  modifiedSettings.measurementNoise.diagonal().setConstant(1e-7);
  modifiedSettings.scaling = -1.0;
  modifiedSettings.transformation << 0.8, 0.2;
  modifiedSettings.parameterSpread << 0.1;
  mjukf::ModifiedJointUkf<Tank> modified(Tank(), x0, theta0, modifiedSettings);

  const Tank::Meas y(0.01, 0.0);
  const bool ok = joint.timeUpdate(0.0, 1e-3) == mjukf::Status::Ok && joint.measurementUpdate(y) == mjukf::Status::Ok &&
                  modified.timeUpdate(0.0, 1e-3) == mjukf::Status::Ok &&
                  modified.measurementUpdate(y) == mjukf::Status::Ok;
  std::printf("downstream: %s, k_flow JUKF %.6f MJUKF %.6f\n", ok ? "ok" : "FAILED", joint.parameters()(0),
              modified.parameters()(0));
  return ok ? 0 : 1;
}
