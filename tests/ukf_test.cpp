// On a linear-Gaussian model the UKF is the Kalman filter: the sigma points carry mean and covariance
// through a linear map exactly, so any difference beyond rounding is a bug in the filter.

#include <random>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "mjukf/simulation.hpp"
#include "mjukf/ukf.hpp"
#include "test_support.hpp"

namespace {

using mjukf::Status;

// A textbook Kalman filter on the discrete model x⁺ = F x + c(t), y = C x.
//
// With `gainWithoutQ` it forms the gain from F P Fᵀ instead of F P Fᵀ + Q, which is what the paper's
// Algorithm 1 does on a linear model: its measurement update reuses the propagated sigma points, whose
// spread carries F P Fᵀ but not the Q added afterwards.
template <int M>
struct KalmanFilter {
  Eigen::Vector3d x;
  Eigen::Matrix3d P;
  bool gainWithoutQ = false;
  Eigen::Matrix3d propagatedP = Eigen::Matrix3d::Zero();  // F P Fᵀ

  void predict(const Eigen::Matrix3d& F, const Eigen::Vector3d& c, const Eigen::Matrix3d& Q) {
    x = F * x + c;
    propagatedP = F * P * F.transpose();
    P = propagatedP + Q;
  }
  void update(const Eigen::Matrix<double, M, 3>& C, const Eigen::Matrix<double, M, M>& R,
              const Eigen::Matrix<double, M, 1>& y) {
    const Eigen::Matrix3d& Pg = gainWithoutQ ? propagatedP : P;
    const Eigen::Matrix<double, M, M> S = C * Pg * C.transpose() + R;
    const Eigen::Matrix<double, 3, M> K = Pg * C.transpose() * S.inverse();
    x += K * (y - C * x);
    P -= K * S * K.transpose();
  }
};

// The integrator applied to a linear model is the affine map x ↦ F x + c(t): read F off the images of
// the unit vectors with the input switched off, and c(t) off the image of zero with it on.
template <class Model>
void discretise(const Model& model, double t, double h, int steps, Eigen::Matrix3d& F, Eigen::Vector3d& c) {
  const mjukf::ITrBdf2<double> stepper;
  const typename Model::Param none;
  const auto ignore = [](long, double, const Eigen::Vector3d&) {};
  auto advance = [&](const Eigen::Vector3d& x, bool withInput) {
    return withInput ? mjukf::simulate(model, stepper, x, none, t, h, steps, ignore)
                     : mjukf::simulate(model, stepper, x, Model::Input::Zero(), none, t, h, steps, ignore);
  };
  for (int i = 0; i < 3; ++i) F.col(i) = advance(Eigen::Vector3d::Unit(i), false);
  c = advance(Eigen::Vector3d::Zero(), true);
}

enum class Update { Redraw, PaperAlgorithm1 };

template <int M, class PointSet = mjukf::MerweScaled>
void expectUkfEqualsKalmanFilter(const mjukf::SigmaPointParameters<double>& sigma, int stepsPerUpdate,
                                 Update update = Update::Redraw) {
  using Model = mjukf::testing::LinearModel<M>;
  Model model;
  if constexpr (M == 1) model.C << 0.0, 0.0, 1.0;  // only the third state: the others must be inferred

  std::mt19937_64 rng(1234);
  std::normal_distribution<double> normal;
  using Filter = mjukf::Ukf<Model, mjukf::DefaultIntegrator<Model>, PointSet>;
  typename Filter::Settings settings;
  settings.sigmaPoints = sigma;
  settings.initialCovariance = mjukf::testing::randomCovariance<3>(rng);
  settings.processNoise = mjukf::testing::randomCovariance<3>(rng, 1e-3);
  settings.measurementNoise = 0.05 * Eigen::Matrix<double, M, M>::Identity();
  settings.redrawPointsForUpdate = update == Update::Redraw;
  const Eigen::Vector3d x0(0.3, -0.2, 1.0);
  Filter ukf(model, x0, typename Model::Param(), settings);
  KalmanFilter<M> kf{x0, settings.initialCovariance, update == Update::PaperAlgorithm1};

  const double h = 0.01;
  Eigen::Vector3d truth(1.0, 0.0, -1.0);
  for (int k = 0; k < 100; ++k) {
    const double t = k * stepsPerUpdate * h;
    Eigen::Matrix3d F;
    Eigen::Vector3d c;
    discretise(model, t, h, stepsPerUpdate, F, c);
    ASSERT_EQ(ukf.timeUpdate(t, h, stepsPerUpdate), Status::Ok);
    kf.predict(F, c, settings.processNoise);
    truth = F * truth + c;
    Eigen::Matrix<double, M, 1> y = model.C * truth;
    for (int i = 0; i < M; ++i) y(i) += 0.2 * normal(rng);
    ASSERT_EQ(ukf.measurementUpdate(y), Status::Ok);
    kf.update(model.C, settings.measurementNoise, y);

    ASSERT_LT((ukf.state() - kf.x).cwiseAbs().maxCoeff(), 1e-10) << "step " << k;
    ASSERT_LT((ukf.covariance() - kf.P).cwiseAbs().maxCoeff(), 1e-10) << "step " << k;
  }
}

TEST(Ukf, EqualsKalmanFilterOnLinearModelFullyObserved) { expectUkfEqualsKalmanFilter<3>({1.0, 2.0, 0.0}, 1); }

TEST(Ukf, EqualsKalmanFilterOnLinearModelPartiallyObserved) { expectUkfEqualsKalmanFilter<1>({1.0, 2.0, 0.0}, 1); }

TEST(Ukf, EqualsKalmanFilterWithOtherScalings) {
  expectUkfEqualsKalmanFilter<3>({0.5, 2.0, 1.0}, 1);
  expectUkfEqualsKalmanFilter<1>({1e-2, 2.0, 0.0}, 1);
}

TEST(Ukf, TimeUpdateOverSeveralStepsEqualsKalmanFilterOverTheirProduct) {
  expectUkfEqualsKalmanFilter<3>({1.0, 2.0, 0.0}, 5);
  expectUkfEqualsKalmanFilter<1>({1.0, 2.0, 0.0}, 3);
}

TEST(Ukf, PaperAlgorithm1EqualsKalmanFilterWhoseGainOmitsQ) {
  expectUkfEqualsKalmanFilter<3>({1.0, 2.0, 0.0}, 1, Update::PaperAlgorithm1);
  expectUkfEqualsKalmanFilter<1>({1.0, 2.0, 0.0}, 1, Update::PaperAlgorithm1);
  expectUkfEqualsKalmanFilter<1>({0.5, 2.0, 1.0}, 4, Update::PaperAlgorithm1);
}

// The cubature set (2L points, weights 1/2L, no centre point) carries a Gaussian through a linear map
// exactly too: with redrawn points the cubature Kalman filter is the Kalman filter, and with the paper's
// reuse of the propagated points it omits Q from the gain as the scaled set does. Its α, β, κ are not
// used, so any setting gives the same filter.
TEST(Ukf, CubatureSetEqualsKalmanFilterOnLinearModel) {
  expectUkfEqualsKalmanFilter<3, mjukf::Cubature>({1.0, 2.0, 0.0}, 1);
  expectUkfEqualsKalmanFilter<1, mjukf::Cubature>({0.3, -1.0, 5.0}, 3);
  expectUkfEqualsKalmanFilter<1, mjukf::Cubature>({1.0, 2.0, 0.0}, 1, Update::PaperAlgorithm1);
}

TEST(Ukf, HeldInputEqualsSignalWhenTheSignalIsConstant) {
  using Model = mjukf::testing::LinearModel<3>;
  struct ConstantInputModel : Model {
    Input input(double) const { return Input::Constant(0.7); }
  };
  typename mjukf::Ukf<ConstantInputModel>::Settings settings;
  settings.initialCovariance = Eigen::Matrix3d::Identity();
  settings.processNoise = 1e-3 * Eigen::Matrix3d::Identity();
  settings.measurementNoise = 0.1 * Eigen::Matrix3d::Identity();
  mjukf::Ukf<ConstantInputModel> signal(ConstantInputModel(), Eigen::Vector3d::Ones(), Model::Param(), settings);
  auto held = signal;
  ASSERT_EQ(signal.timeUpdate(0.0, 0.01, 4), Status::Ok);
  ASSERT_EQ(held.timeUpdate(0.0, 0.01, Model::Input::Constant(0.7), 4), Status::Ok);
  EXPECT_EQ(signal.state(), held.state());
  EXPECT_EQ(signal.covariance(), held.covariance());
  ASSERT_EQ(signal.propagateMean(0.04, 0.01), Status::Ok);
  ASSERT_EQ(held.propagateMean(0.04, 0.01, Model::Input::Constant(0.7)), Status::Ok);
  EXPECT_EQ(signal.state(), held.state());
}

TEST(Ukf, PropagateMeanMovesTheMeanAloneAndDropsThePoints) {
  using Model = mjukf::testing::LinearModel<3>;
  typename mjukf::Ukf<Model>::Settings settings;
  settings.initialCovariance = Eigen::Matrix3d::Identity();
  settings.processNoise = 1e-3 * Eigen::Matrix3d::Identity();
  settings.measurementNoise = 0.1 * Eigen::Matrix3d::Identity();
  mjukf::Ukf<Model> ukf(Model(), Eigen::Vector3d(1.0, 2.0, 3.0), Model::Param(), settings);
  ASSERT_EQ(ukf.timeUpdate(0.0, 0.01), Status::Ok);
  EXPECT_TRUE(ukf.hasPropagatedPoints());
  const Eigen::Matrix3d P = ukf.covariance();
  Eigen::Matrix3d F;
  Eigen::Vector3d c;
  discretise(Model(), 0.01, 0.01, 1, F, c);
  const Eigen::Vector3d expected = F * ukf.state() + c;
  ASSERT_EQ(ukf.propagateMean(0.01, 0.01), Status::Ok);
  EXPECT_LT((ukf.state() - expected).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_EQ(ukf.covariance(), P);
  EXPECT_FALSE(ukf.hasPropagatedPoints());
}

}  // namespace
