// Built against the installed package: both umbrella headers (the core and the paper layer) and one
// filter step of each kind.
#include <cstdio>

#include <mjukf/mjukf.hpp>
#include <mjukf/paper/paper.hpp>

int main() {
  using Tank = mjukf::paper::CoupledTankExperiment<double>;
  mjukf::JointUkf<Tank::Model> joint(Tank::Model(), Tank::initialState(), Tank::initialParameters(), Tank::jointUkf());
  mjukf::ModifiedJointUkf<Tank::Model> modified(Tank::Model(), Tank::initialState(), Tank::initialParameters(),
                                                Tank::modifiedJointUkf());
  const Tank::Model::Meas y(0.01, 0.0);
  const bool ok = joint.timeUpdate(0.0, 1e-3) == mjukf::Status::Ok && joint.measurementUpdate(y) == mjukf::Status::Ok &&
                  modified.timeUpdate(0.0, 1e-3) == mjukf::Status::Ok &&
                  modified.measurementUpdate(y) == mjukf::Status::Ok;
  std::printf("downstream: %s, k_flow JUKF %.6f MJUKF %.6f\n", ok ? "ok" : "FAILED", joint.parameters()(0),
              modified.parameters()(0));
  return ok ? 0 : 1;
}
