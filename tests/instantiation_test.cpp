// Every class template explicitly instantiated for float and double, so that every member compiles
// for both (a member that is never called is otherwise never compiled), and a float filter runs.

#include <gtest/gtest.h>

#include "mjukf/mjukf.hpp"
#include "mjukf/models/coupled_tank.hpp"
#include "mjukf/models/flexible_joint.hpp"
#include "paper/paper.hpp"

namespace mjukf {

#define MJUKF_INSTANTIATE_FOR(Scalar)                                                                                 \
  template class MerweScaledSigmaPoints<Scalar, 1>;                                                                   \
  template class MerweScaledSigmaPoints<Scalar, 6>;                                                                   \
  template class detail::Estimate<Scalar, 4, 4>;                                                                      \
  template class detail::Estimate<Scalar, 3, 2, Cubature>;                                                            \
  template class detail::Estimate<Scalar, 4, 4, MerweScaled, SquareRootCovariance>;                                   \
  template class detail::Estimate<Scalar, 1, 2, Cubature, SquareRootCovariance>;                                      \
  template class Ukf<models::CoupledTank<Scalar>, ITrBdf2<Scalar>, MerweScaled, SquareRootCovariance>;                \
  template class JointUkf<models::FlexibleJoint<Scalar>, ITrBdf2<Scalar>, MerweScaled, SquareRootCovariance>;         \
  template class ModifiedJointUkf<models::FlexibleJoint<Scalar>, ITrBdf2<Scalar>, MerweScaled, SquareRootCovariance>; \
  template class DualUkf<models::CoupledTank<Scalar>, ITrBdf2<Scalar>, MerweScaled, SquareRootCovariance>;            \
  template class JointUkf<models::CoupledTank<Scalar>, Rk4<Scalar>, Cubature, SquareRootCovariance>;                  \
  template class CubatureSigmaPoints<Scalar, 3>;                                                                      \
  template class Ukf<models::CoupledTank<Scalar>, Rk4<Scalar>, Cubature>;                                             \
  template class JointUkf<models::FlexibleJoint<Scalar>, Rk4<Scalar>, Cubature>;                                      \
  template class DualUkf<models::FlexibleJoint<Scalar>, ITrBdf2<Scalar>, Cubature>;                                   \
  template class ITrBdf2<Scalar>;                                                                                     \
  template class ExplicitTrBdf2<Scalar>;                                                                              \
  template class Rk4<Scalar>;                                                                                         \
  template class TrBdf2<Scalar>;                                                                                      \
  template class JointUkf<models::FlexibleJoint<Scalar>, Rk4<Scalar>>;                                                \
  template class ModifiedJointUkf<models::CoupledTank<Scalar>, ExplicitTrBdf2<Scalar>>;                               \
  template class Ukf<models::FlexibleJoint<Scalar>, TrBdf2<Scalar>>;                                                  \
  template struct models::CoupledTank<Scalar>;                                                                        \
  template struct models::FlexibleJoint<Scalar>;                                                                      \
  template class Ukf<models::CoupledTank<Scalar>>;                                                                    \
  template class Ukf<models::FlexibleJoint<Scalar>>;                                                                  \
  template class JointUkf<models::CoupledTank<Scalar>>;                                                               \
  template class JointUkf<models::FlexibleJoint<Scalar>>;                                                             \
  template class ModifiedJointUkf<models::CoupledTank<Scalar>>;                                                       \
  template class ModifiedJointUkf<models::FlexibleJoint<Scalar>>;                                                     \
  template class DualUkf<models::CoupledTank<Scalar>>;                                                                \
  template class DualUkf<models::FlexibleJoint<Scalar>>;                                                              \
  template struct DualUkfSettings<Scalar, 4, 2, 4>;                                                                   \
  template struct UkfSettings<Scalar, 4, 4>;                                                                          \
  template struct JointUkfSettings<Scalar, 4, 2, 4>;                                                                  \
  template struct ModifiedJointUkfSettings<Scalar, 4, 2, 4>;                                                          \
  template struct UpdateDiagnostics<Scalar, 4>;                                                                       \
  template class paper::RmseAccumulator<Scalar, 2>;                                                                   \
  template struct paper::CoupledTankExperiment<Scalar>;                                                               \
  template struct paper::FlexibleJointExperiment<Scalar>;

MJUKF_INSTANTIATE_FOR(float)
MJUKF_INSTANTIATE_FOR(double)

#undef MJUKF_INSTANTIATE_FOR

}  // namespace mjukf

namespace {

// The robot's MJUKF in float over 20 s of a noiseless simulation (made with the double model): it
// must run without a refused step and converge, and float must track double. Rounding θ̂ ≈ 0.2 alone
// (ε_float · 0.2 ≈ 1.2e-8 per update, a random walk over 4000 updates) would give ~1e-6; rounding of
// the states feeds eq. 9 through every sigma point on top of that, and the measured difference is
// 2e-6 to 4e-6 (K_τ) depending on the order of operations in the update. 1e-5 is ~8 ε_float relative
// to θ̂: far below the filter's own error (2.5e-4 here), and a float path that lost precision
// somewhere (a sum in the wrong order, a float RMSE, a cast through float in double code) exceeds it.
TEST(Instantiation, FloatFilterRunsAndAgreesWithDouble) {
  using RobotD = mjukf::paper::FlexibleJointExperiment<double>;
  using RobotF = mjukf::paper::FlexibleJointExperiment<float>;
  const long rows = 20001;
  std::vector<RobotD::Model::Meas> truth(rows);
  mjukf::simulate(RobotD::Model(), mjukf::ITrBdf2<double>(), RobotD::State::Zero(), RobotD::Model::trueParameters(),
                  0.0, 1e-3, rows - 1, [&](long k, double, const RobotD::State& x) { truth[k] = x; });
  mjukf::ModifiedJointUkf<RobotF::Model> single(RobotF::Model(), RobotF::initialState(), RobotF::initialParameters(),
                                                RobotF::modifiedJointUkf());
  mjukf::ModifiedJointUkf<RobotD::Model> twice(RobotD::Model(), RobotD::initialState(), RobotD::initialParameters(),
                                               RobotD::modifiedJointUkf());
  const auto runF = mjukf::paper::runSchedule(
      single, rows, 1e-3f, 5, [&](long k) { return RobotF::Model::Meas(truth[k].cast<float>()); },
      [](long, const auto&) {});
  const auto runD = mjukf::paper::runSchedule(
      twice, rows, 1e-3, 5, [&](long k) { return truth[k]; }, [](long, const auto&) {});
  ASSERT_EQ(runF.status, mjukf::Status::Ok) << "row " << runF.row;
  ASSERT_EQ(runD.status, mjukf::Status::Ok) << "row " << runD.row;
  const Eigen::Vector2d estimateF = single.parameters().cast<double>();
  std::printf("float (K_tau, m) = (%.6f, %.6f), double (%.6f, %.6f)\n", estimateF(0), estimateF(1),
              twice.parameters()(0), twice.parameters()(1));
  // Converged: a tenth of the initial error (0.05 in K_τ, 0.06 in m) or less.
  EXPECT_LT((estimateF - RobotD::Model::trueParameters()).cwiseAbs().maxCoeff(), 0.005);
  EXPECT_LT((estimateF - twice.parameters()).cwiseAbs().maxCoeff(), 1e-5);
}

}  // namespace
