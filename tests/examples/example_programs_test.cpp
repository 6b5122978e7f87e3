// The example programs end to end, run as a user runs them: every subcommand on a short horizon,
// `estimate` against the conformance RMSEs on the reference files, the dual UKF on the same files,
// `simulate` followed by `estimate`, and the error paths (malformed CSV → exit 2 with the line number;
// bad command line → usage, 64). Failed and interrupted runs' files: output_files_test.cpp.

#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/csv.hpp"
#include "run_program.hpp"

namespace {

namespace fs = std::filesystem;
using mjukf::examples::readCsv;
using mjukf::program_tests::Result;
using mjukf::program_tests::run;
using mjukf::program_tests::scratch;
using mjukf::program_tests::shellQuote;
using mjukf::program_tests::writeFile;

const std::string kTank = MJUKF_COUPLED_TANK;
const std::string kRobot = MJUKF_FLEXIBLE_JOINT;
const std::string kData = MJUKF_DATA_DIR;

// The value printed as `key: value` (NaN when missing).
double printed(const std::string& output, const std::string& key) {
  std::smatch match;
  if (!std::regex_search(output, match, std::regex(key + ": ([-+0-9.eE]+)"))) return std::nan("");
  return std::stod(match[1]);
}

// ---------------------------------------------------------------------------------------------
// estimate on the reference files: the conformance RMSEs of docs/plants.md §6 to 1e-6 relative.

struct ConformanceCase {
  const char* name;
  const std::string* program;
  const char* filter;
  const char* file;
  std::vector<double> rmse;
};
void PrintTo(const ConformanceCase& c, std::ostream* os) { *os << c.name; }

class EstimateConformance : public ::testing::TestWithParam<ConformanceCase> {};

TEST_P(EstimateConformance, ReproducesTheConformanceRmse) {
  const auto& c = GetParam();
  const std::string data = kData + "/" + c.file;
  const std::string out = scratch("estimates.csv");
  const Result r = run(*c.program + " estimate --filter " + c.filter + " --data " + data + " --out " + out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  for (std::size_t i = 0; i < c.rmse.size(); ++i) {
    const double rmse = printed(r.output, "rmse_theta" + std::to_string(i + 1));
    EXPECT_NEAR(rmse, c.rmse[i], 1e-6 * c.rmse[i]) << r.output;
  }
  EXPECT_GE(printed(r.output, "loop_seconds"), 0.0) << r.output;
  // Exactly one output row per data row, row 0 the initial estimate at t = 0.
  const auto estimates = readCsv(out);
  EXPECT_EQ(estimates.rows(), readCsv(data).rows());
  EXPECT_EQ(estimates.column("t").front(), 0.0);
  EXPECT_EQ(estimates.column("x1").front(), 0.0);
}

// The health at the end of a run (docs/robustness.md, "The health monitor"): the paper's R = 1e-7 on
// the tank's 30 dB reference file (noise variance 0.09) raises InnovationsTooLarge in the first block;
// R = 0.09 runs the whole file without an alarm.
TEST(Estimate, PrintsTheHealthOfTheRun) {
  const std::string data = kData + "/coupled_tank_reference.csv";
  const std::string out = scratch("estimates.csv");
  const Result paper = run(kTank + " estimate --filter jukf --data " + data + " --out " + out);
  ASSERT_EQ(paper.exitCode, 0) << paper.output;
  EXPECT_NE(
      paper.output.find("\nhealth: innovations larger than their covariance (first raised at measurement update 50;"),
      std::string::npos)
      << paper.output;
  EXPECT_NE(paper.output.find("\nhealth, last block: normalised NIS "), std::string::npos) << paper.output;
  const Result noise = run(kTank + " estimate --filter jukf --r 0.09 --data " + data + " --out " + out);
  ASSERT_EQ(noise.exitCode, 0) << noise.output;
  EXPECT_NE(noise.output.find("\nhealth: ok (no alarm in 2000 blocks"), std::string::npos) << noise.output;
}

INSTANTIATE_TEST_SUITE_P(
    ReferenceFiles, EstimateConformance,
    ::testing::Values(
        ConformanceCase{"TankJukf", &kTank, "jukf", "coupled_tank_reference.csv", {0.2919404233}},
        ConformanceCase{"TankMjukf", &kTank, "mjukf", "coupled_tank_reference.csv", {0.2434184329}},
        ConformanceCase{"RobotJukf", &kRobot, "jukf", "flexible_joint_reference.csv", {0.02671036066, 0.03426798571}},
        ConformanceCase{
            "RobotMjukf", &kRobot, "mjukf", "flexible_joint_reference.csv", {0.006717243853, 0.008727060131}}),
    [](const auto& info) { return std::string(info.param.name); });

// ---------------------------------------------------------------------------------------------
// estimate --filter dual on the reference files. The paper has no dual filter, so there is no
// conformance number: the RMSEs are asserted loosely, against what a filter that learned something
// must beat. Printed by `estimate` on this machine (docs/reproducing-the-paper.md):
//   tank,  prior:   rmse_theta1 3.791132388                      (final k_flow 2.50968, truth 6)
//   tank,  updated: rmse_theta1 3.791132389
//   robot, prior:   rmse_theta1 0.006710709652, rmse_theta2 0.009822916915
//   robot, updated: rmse_theta1 0.006587243043, rmse_theta2 0.009692712986
// The tank's dual, observing with R plus the data's noise variance (the preset), learns slowly: after
// 200 s it has moved from the first guess 2 only to 2.51, so its RMSE is just below the first guess's
// error of 4, and the test checks that it moved towards the truth. The robot's dual beats JUKF's
// conformance RMSEs (0.0267, 0.0343), themselves below the first guess's errors (0.05, 0.06).

struct DualCase {
  const char* name;
  const std::string* program;
  const char* ordering;
  const char* file;
  std::vector<double> bound;  // each RMSE must be below this
};
void PrintTo(const DualCase& c, std::ostream* os) { *os << c.name; }

class DualEstimate : public ::testing::TestWithParam<DualCase> {};

TEST_P(DualEstimate, RunsAndLearnsTheParameters) {
  const auto& c = GetParam();
  const std::string data = kData + "/" + c.file;
  const std::string out = scratch("estimates.csv");
  const Result r =
      run(*c.program + " estimate --filter dual --ordering " + c.ordering + " --data " + data + " --out " + out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find(std::string("dual (ordering: ") + c.ordering + ") on "), std::string::npos) << r.output;
  for (std::size_t i = 0; i < c.bound.size(); ++i) {
    const double rmse = printed(r.output, "rmse_theta" + std::to_string(i + 1));
    EXPECT_TRUE(std::isfinite(rmse)) << r.output;
    EXPECT_GT(rmse, 0.0) << r.output;
    EXPECT_LT(rmse, c.bound[i]) << "theta" << i + 1 << "\n" << r.output;
  }
  const auto estimates = readCsv(out);
  ASSERT_EQ(estimates.rows(), readCsv(data).rows());
  if (c.program == &kTank) {  // moved from the first guess 2 towards the truth 6, without passing it
    const double last = estimates.column("theta1").back();
    EXPECT_GT(last, 2.25) << r.output;
    EXPECT_LT(last, 6.0) << r.output;
  }
}

INSTANTIATE_TEST_SUITE_P(
    ReferenceFiles, DualEstimate,
    ::testing::Values(
        DualCase{"TankPrior", &kTank, "prior", "coupled_tank_reference.csv", {4.0}},
        DualCase{"TankUpdated", &kTank, "updated", "coupled_tank_reference.csv", {4.0}},
        DualCase{"RobotPrior", &kRobot, "prior", "flexible_joint_reference.csv", {0.02671036066, 0.03426798571}},
        DualCase{"RobotUpdated", &kRobot, "updated", "flexible_joint_reference.csv", {0.02671036066, 0.03426798571}}),
    [](const auto& info) { return std::string(info.param.name); });

// The default ordering is `prior`; `updated` is another filter (different RMSEs on the robot).
TEST(Estimate, DualOrderingDefaultsToPriorAndMatters) {
  const std::string data = kData + "/flexible_joint_reference.csv";
  const std::string dual = kRobot + " estimate --filter dual --data " + data;
  const Result byDefault = run(dual + " --out " + scratch("a.csv"));
  const Result prior = run(dual + " --out " + scratch("b.csv") + " --ordering prior");
  const Result updated = run(dual + " --out " + scratch("c.csv") + " --ordering updated");
  ASSERT_EQ(byDefault.exitCode, 0) << byDefault.output;
  ASSERT_EQ(prior.exitCode, 0) << prior.output;
  ASSERT_EQ(updated.exitCode, 0) << updated.output;
  EXPECT_NE(byDefault.output.find("dual (ordering: prior)"), std::string::npos) << byDefault.output;
  for (const char* key : {"rmse_theta1", "rmse_theta2"}) {
    EXPECT_EQ(printed(byDefault.output, key), printed(prior.output, key));
    EXPECT_NE(printed(prior.output, key), printed(updated.output, key));
  }
}

// --p0, --q and --r set the dual's state filter (the preset's on the robot: the UKF's 0.5 and 1e-5, and
// R = 0.05, the data's noise variance), --r-theta what is added to its parameter filter's observation
// noise H P⁻ Hᵀ + R (nothing in the preset).
TEST(Estimate, DualSettingsAreOverridable) {
  const std::string data = kData + "/flexible_joint_reference.csv";
  const std::string dual = kRobot + " estimate --filter dual --data " + data;
  const Result preset = run(dual + " --out " + scratch("a.csv"));
  const Result same = run(dual + " --out " + scratch("b.csv") +
                          " --p0 0.5,0.5,0.5,0.5 --q 1e-5 --r 0.05 --r-theta 0 --theta0 0.1,0.15 --every 5");
  const Result otherR = run(dual + " --out " + scratch("c.csv") + " --r 2e-3");
  const Result otherQ = run(dual + " --out " + scratch("d.csv") + " --q 1e-4");
  const Result otherRTheta = run(dual + " --out " + scratch("e.csv") + " --r-theta 1e-2");
  for (const Result* r : {&preset, &same, &otherR, &otherQ, &otherRTheta}) ASSERT_EQ(r->exitCode, 0) << r->output;
  EXPECT_EQ(printed(preset.output, "rmse_theta1"), printed(same.output, "rmse_theta1"));
  for (const Result* r : {&otherR, &otherQ, &otherRTheta})
    EXPECT_NE(printed(preset.output, "rmse_theta1"), printed(r->output, "rmse_theta1")) << r->output;
  // Measured: adding 1e-2 to an observation noise of H P⁻ Hᵀ + 0.05 moves K_τ's RMSE from 0.000676 to
  // 0.0006759121 (0.0006759315 when the parameter filter's points were spread with α = 1; it was 0.0124
  // against 0.0067 when the parameter filter observed with R plus this alone).
  EXPECT_NEAR(printed(otherRTheta.output, "rmse_theta1"), 0.0006759120762, 1e-6 * 0.0006759120762)
      << otherRTheta.output;
}

// ---------------------------------------------------------------------------------------------
// simulate

TEST(Simulate, WritesOneRowPerStepWithTruthAndThirtyDecibelNoise) {
  const std::string out = scratch("robot.csv");
  const Result r = run(kRobot + " simulate --out " + out + " --duration 2 --seed 3");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto table = readCsv(out);
  const std::vector<std::string> header{"t",       "y1",      "y2",      "y3",          "y4",         "x1_true",
                                        "x2_true", "x3_true", "x4_true", "theta1_true", "theta2_true"};
  EXPECT_EQ(table.names(), header);
  ASSERT_EQ(table.rows(), 2001u);
  EXPECT_NEAR(table.column("t")[1234], 1.234, 1e-12);

  // docs/plants.md §4: σ² = var(all states) / 10^(30/10), the same σ on every channel. The sample variance
  // of N = 4 × 2001 residuals y − x has relative standard error sqrt(2/N) ≈ 1.6 %, so 8 % is 5 of those.
  double sum = 0, squares = 0, noise = 0;
  const double n = 4.0 * double(table.rows());
  for (int c = 1; c <= 4; ++c) {
    const auto& x = table.column("x" + std::to_string(c) + "_true");
    const auto& y = table.column("y" + std::to_string(c));
    for (std::size_t k = 0; k < x.size(); ++k) {
      sum += x[k];
      squares += x[k] * x[k];
      noise += (y[k] - x[k]) * (y[k] - x[k]);
    }
  }
  const double signalVariance = squares / n - (sum / n) * (sum / n);
  EXPECT_NEAR(noise / n, signalVariance / 1000.0, 0.08 * signalVariance / 1000.0);
  for (double theta : table.column("theta1_true")) ASSERT_EQ(theta, 0.15);
  for (double theta : table.column("theta2_true")) ASSERT_EQ(theta, 0.21);
}

TEST(Simulate, ChangeAtSwitchesTheRobotParameters) {
  const std::string out = scratch("change.csv");
  const Result r = run(kRobot + " simulate --out " + out + " --duration 2 --change-at 1");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto table = readCsv(out);
  ASSERT_EQ(table.rows(), 2001u);
  for (std::size_t k = 0; k < table.rows(); ++k) {
    ASSERT_EQ(table.column("theta1_true")[k], k < 1000 ? 0.15 : 0.10) << "row " << k;
    ASSERT_EQ(table.column("theta2_true")[k], k < 1000 ? 0.21 : 0.30) << "row " << k;
  }
}

TEST(Simulate, SameSeedSameFileNoNoiseAtInfiniteSnr) {
  const std::string a = scratch("a.csv"), b = scratch("b.csv"), clean = scratch("clean.csv");
  ASSERT_EQ(run(kTank + " simulate --out " + a + " --duration 1 --seed 5").exitCode, 0);
  ASSERT_EQ(run(kTank + " simulate --out " + b + " --duration 1 --seed 5").exitCode, 0);
  EXPECT_EQ(readCsv(a).column("y1"), readCsv(b).column("y1"));
  ASSERT_EQ(run(kTank + " simulate --out " + clean + " --duration 1 --snr-db inf").exitCode, 0);
  const auto table = readCsv(clean);
  EXPECT_EQ(table.column("y1"), table.column("x1_true"));
  EXPECT_EQ(table.column("y2"), table.column("x2_true"));
}

// ---------------------------------------------------------------------------------------------
// simulate, then estimate: the parameters are recovered.
//
// Tolerance. The RMSE of a parameter over the paper's window is a random variable over noise
// realisations at the fixed 30 dB SNR; the conformance RMSE r_c on the reference file is one draw of
// it. The estimation error decorrelates in about τ = 1 s (the robot's input period; the tank's
// estimates wander on the same scale, see the figures), so a window of length W holds about
// N = W / τ independent samples; the mean square then has a relative standard deviation of about
// sqrt(2 / N), and the RMSE half of that, sqrt(1 / (2N)). We allow 6 of those above r_c:
//   bound = r_c (1 + 6 sqrt(1 / (2N))),  robot W = 18 s → ×2.0,  tank W = 180 s → ×1.32.
// (Measured over seeds 1–10: at most ×1.55 for the robot's MJUKF, ×1.005 for the tank.) That the bound
// is far below the error of the first guess (K_τ 0.05, m 0.06, k_flow 4) shows the estimate moved to the truth.

struct RecoveryCase {
  const char* name;
  const std::string* program;
  const char* filter;
  double window;  // s
  std::vector<double> conformanceRmse;
};
void PrintTo(const RecoveryCase& c, std::ostream* os) { *os << c.name; }

class SimulateThenEstimate : public ::testing::TestWithParam<RecoveryCase> {};

TEST_P(SimulateThenEstimate, RecoversTheParameters) {
  const auto& c = GetParam();
  const std::string data = scratch("simulated.csv"), out = scratch("estimates.csv");
  ASSERT_EQ(run(*c.program + " simulate --out " + data + " --seed 7").exitCode, 0);
  const Result r = run(*c.program + " estimate --filter " + c.filter + " --data " + data + " --out " + out);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("truth: theta*_true columns"), std::string::npos) << r.output;
  const double factor = 1 + 6 * std::sqrt(1 / (2 * c.window / 1.0));
  for (std::size_t i = 0; i < c.conformanceRmse.size(); ++i)
    EXPECT_LT(printed(r.output, "rmse_theta" + std::to_string(i + 1)), factor * c.conformanceRmse[i]) << r.output;
}

INSTANTIATE_TEST_SUITE_P(
    BothPlants, SimulateThenEstimate,
    ::testing::Values(RecoveryCase{"TankJukf", &kTank, "jukf", 180, {0.2919404233}},
                      RecoveryCase{"TankMjukf", &kTank, "mjukf", 180, {0.2434184329}},
                      RecoveryCase{"RobotJukf", &kRobot, "jukf", 18, {0.02671036066, 0.03426798571}},
                      RecoveryCase{"RobotMjukf", &kRobot, "mjukf", 18, {0.006717243853, 0.008727060131}}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(Estimate, UkfWritesTheFixedParametersItWasGiven) {
  const std::string data = scratch("tank.csv"), out = scratch("ukf.csv");
  ASSERT_EQ(run(kTank + " simulate --out " + data + " --duration 2").exitCode, 0);
  const Result r = run(kTank + " estimate --filter ukf --data " + data + " --out " + out + " --theta0 5.5");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto table = readCsv(out);
  EXPECT_EQ(table.names(), (std::vector<std::string>{"t", "x1", "x2", "theta1"}));
  ASSERT_EQ(table.rows(), 2001u);
  for (double theta : table.column("theta1")) ASSERT_EQ(theta, 5.5);
  EXPECT_NEAR(printed(r.output, "rmse_theta1"), 0.5, 1e-12);  // |5.5 − 6| on every row (short run: all rows)
}

TEST(Estimate, SettingsAreOverridable) {
  const std::string data = kData + "/flexible_joint_reference.csv";
  const Result paper = run(kRobot + " estimate --filter mjukf --data " + data + " --out " + scratch("a.csv"));
  const Result same = run(kRobot + " estimate --filter mjukf --data " + data + " --out " + scratch("b.csv") +
                          " --xi -0.0025 --every 5 --transform 0.3,0.3,0.2,0.2,0.2,0.2,0.3,0.3 --p-theta 0.01,0.01" +
                          " --r 1e-3 --q 1e-5 --p0 0.5,0.5,0.5,0.5 --theta0 0.1,0.15 --alpha 1 --beta 2 --kappa 0");
  const Result other =
      run(kRobot + " estimate --filter mjukf --data " + data + " --out " + scratch("c.csv") + " --xi -0.0015");
  ASSERT_EQ(paper.exitCode, 0) << paper.output;
  ASSERT_EQ(same.exitCode, 0) << same.output;
  ASSERT_EQ(other.exitCode, 0) << other.output;
  EXPECT_EQ(printed(paper.output, "rmse_theta1"), printed(same.output, "rmse_theta1"));
  EXPECT_NE(printed(paper.output, "rmse_theta1"), printed(other.output, "rmse_theta1"));
}

// Spreadsheet programs often start a CSV file with a UTF-8 byte order mark: it is not part of the name.
TEST(Estimate, AcceptsAUtf8ByteOrderMark) {
  const std::string data = scratch("tank.csv"), withMark = scratch("bom.csv");
  ASSERT_EQ(run(kTank + " simulate --out " + data + " --duration 0.5").exitCode, 0);
  {
    std::ifstream in(data);
    std::ofstream(withMark) << "\xEF\xBB\xBF" << in.rdbuf();
  }
  const auto table = readCsv(withMark);
  ASSERT_FALSE(table.names().empty());
  EXPECT_EQ(table.names().front(), "t");
  EXPECT_EQ(table.column("y1"), readCsv(data).column("y1"));
  const Result r = run(kTank + " estimate --filter mjukf --data " + withMark + " --out " + scratch("out.csv"));
  EXPECT_EQ(r.exitCode, 0) << r.output;
}

// ---------------------------------------------------------------------------------------------
// paper, on short horizons

TEST(Paper, TankPrintsTheTableAndWritesItsFiles) {
  const std::string dir = scratch("paper");
  const Result r = run(kTank + " paper --duration 3 --runs 3 --out-dir " + dir);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  for (const char* text : {"Table 3", "RMSE k_flow", "77.696", "71.191", "time MJUKF / JUKF", "median of 3 runs",
                           "time dual / JUKF", "the paper has no dual filter", "no published value"})
    EXPECT_NE(r.output.find(text), std::string::npos) << text << "\n" << r.output;
  // The dual column beside JUKF and MJUKF, ours with a number, the paper's with none.
  EXPECT_TRUE(std::regex_search(r.output, std::regex("JUKF +MJUKF +dual +JUKF +MJUKF +dual"))) << r.output;
  EXPECT_TRUE(std::regex_search(
      r.output, std::regex(R"(RMSE k_flow \(\(cm\^3/s\)/V\) +[0-9.]+ +[0-9.]+ +[0-9.]+ +0\.2919 +0\.2434 +- )")))
      << r.output;
  for (const char* file : {"coupled_tank_data.csv", "coupled_tank_jukf.csv", "coupled_tank_mjukf.csv",
                           "coupled_tank_dual.csv", "coupled_tank_table.txt"})
    EXPECT_TRUE(fs::exists(fs::path(dir) / file)) << file;
  EXPECT_EQ(readCsv((fs::path(dir) / "coupled_tank_jukf.csv").string()).rows(), 3001u);
  EXPECT_EQ(readCsv((fs::path(dir) / "coupled_tank_dual.csv").string()).rows(), 3001u);
  // With gnuplot the figures exist, the parameter figure with the dual's curve; without it the program
  // says so instead.
  const bool plotted = fs::exists(fs::path(dir) / "coupled_tank_parameters.png");
  EXPECT_TRUE(plotted || r.output.find("gnuplot") != std::string::npos) << r.output;
  if (plotted) {
    std::ifstream script(fs::path(dir) / "coupled_tank_parameters.gp");
    const std::string text((std::istreambuf_iterator<char>(script)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("coupled_tank_dual.csv"), std::string::npos) << text;
    EXPECT_NE(text.find("title \"dual\""), std::string::npos) << text;
  }
}

TEST(Paper, RobotRunsBothScenariosOnTheGivenFiles) {
  const std::string dir = scratch("paper");
  // Short data files: the first 6 s of the reference files, so that the change at 5 s is inside.
  const auto head = [&](const std::string& file, const std::string& name) {
    std::ifstream in(kData + "/" + file);
    std::ofstream out(scratch(name));
    std::string line;
    for (int i = 0; i < 6002 && std::getline(in, line); ++i) out << line << "\n";
    return scratch(name);
  };
  const std::string data = head("flexible_joint_reference.csv", "short.csv");
  const std::string change = head("flexible_joint_param_change_reference.csv", "short_change.csv");
  const Result r = run(kRobot + " paper --runs 2 --out-dir " + dir + " --data " + data + " --change-data " + change);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  for (const char* text :
       {"Table 4", "RMSE K_tau", "RMSE m", "4.337", "3.717", "parameter change", "xi = -0.0035", "no published value"})
    EXPECT_NE(r.output.find(text), std::string::npos) << text << "\n" << r.output;
  EXPECT_TRUE(std::regex_search(r.output, std::regex("JUKF +MJUKF +dual +JUKF +MJUKF +dual"))) << r.output;
  EXPECT_TRUE(
      std::regex_search(r.output, std::regex(R"(RMSE m \(kg\) +[0-9.]+ +[0-9.]+ +[0-9.]+ +0\.019 +0\.01233 +- )")))
      << r.output;
  // The parameter-change table has the dual column too: RMSE and final estimate of each parameter.
  EXPECT_TRUE(std::regex_search(r.output, std::regex(R"(parameter change[\s\S]*\n +JUKF +MJUKF +dual *\n)")))
      << r.output;
  EXPECT_TRUE(std::regex_search(r.output, std::regex(R"(final K_tau \(truth 0\.1\) +[-0-9.]+ +[-0-9.]+ +[-0-9.]+)")))
      << r.output;
  for (const char* file :
       {"flexible_joint_change_jukf.csv", "flexible_joint_change_mjukf.csv", "flexible_joint_change_dual.csv",
        "flexible_joint_change_data.csv", "flexible_joint_mjukf.csv", "flexible_joint_dual.csv"})
    EXPECT_TRUE(fs::exists(fs::path(dir) / file)) << file;
  // The change data file has no truth columns: the paper's change at 5 s is used.
  const auto truth = readCsv((fs::path(dir) / "flexible_joint_change_data.csv").string());
  EXPECT_EQ(truth.column("theta2_true")[4999], 0.21);
  EXPECT_EQ(truth.column("theta2_true")[5000], 0.30);
}

// --duration sets the length of a fresh simulation: with every data set from a file it would be
// ignored, so it is refused. (The robot's --data alone still simulates the parameter-change run.)
TEST(CommandLine, PaperRefusesDurationWhenNoSimulationUsesIt) {
  const std::string tank = scratch("tank.csv"), robot = scratch("robot.csv");
  ASSERT_EQ(run(kTank + " simulate --out " + tank + " --duration 0.5").exitCode, 0);
  ASSERT_EQ(run(kRobot + " simulate --out " + robot + " --duration 0.5").exitCode, 0);
  const std::string paper = " paper --runs 1 --duration 0.5 --out-dir " + scratch("paper");
  for (const std::string& command :
       {kTank + paper + " --data " + tank, kRobot + paper + " --data " + robot + " --change-data " + robot}) {
    const Result r = run(command);
    EXPECT_EQ(r.exitCode, 64) << command << "\n" << r.output;
    EXPECT_NE(r.output.find("--duration applies to a fresh simulation only"), std::string::npos) << r.output;
  }
  const Result r = run(kRobot + paper + " --data " + robot);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("fresh simulation (0.5 s"), std::string::npos) << r.output;
}

// A duration must give a positive number of steps that fits in memory: 1e300 s overflowed lround
// (undefined behaviour), 1e7 s asked for 1e10 rows.
TEST(CommandLine, DurationIsPositiveAndBounded) {
  const std::string sim = kTank + " simulate --out " + scratch("s.csv");
  for (const std::string& command :
       {sim + " --duration 1e300", sim + " --duration 1e7", sim + " --duration 0", sim + " --duration -1",
        kRobot + " simulate --out " + scratch("s.csv") + " --change-at 1 --duration 1e300",
        kTank + " paper --runs 1 --out-dir " + scratch("paper") + " --duration 1e300",
        kTank + " paper --runs 1 --out-dir " + scratch("paper") + " --duration 0"}) {
    const Result r = run(command);
    EXPECT_EQ(r.exitCode, 64) << command << "\n" << r.output;
    EXPECT_NE(r.output.find("--duration needs a time > 0 s of at most 10000000 steps"), std::string::npos)
        << command << "\n"
        << r.output;
  }
}

// A change time beyond any run is no change at all (it overflowed lround and switched at row 0).
TEST(Simulate, ChangeAtBeyondTheRunChangesNothing) {
  const std::string out = scratch("change.csv");
  const Result r = run(kRobot + " simulate --out " + out + " --duration 0.01 --change-at 1e300");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto table = readCsv(out);
  ASSERT_EQ(table.rows(), 11u);
  for (double theta : table.column("theta1_true")) ASSERT_EQ(theta, 0.15);
  for (double theta : table.column("theta2_true")) ASSERT_EQ(theta, 0.21);
}

// table.txt is checked like every other output: a failed write is exit 1, not a file listed as written,
// and no other file of the run is put in place (they are committed together).
TEST(Paper, FailingToWriteTheTableIsAnError) {
  const fs::path dir = scratch("paper");
  fs::remove_all(dir);
  fs::create_directories(dir / "coupled_tank_table.txt");  // a directory where the file should go
  const Result r = run(kTank + " paper --duration 1 --runs 1 --out-dir " + dir.string());
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("coupled_tank_table.txt: cannot write the file"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("wrote:"), std::string::npos) << r.output;
  std::vector<std::string> left;
  for (const auto& entry : fs::directory_iterator(dir)) left.push_back(entry.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"coupled_tank_table.txt"});
}

// The table lines are built without a fixed-size buffer: a long --data path is printed whole.
TEST(Paper, PrintsALongDataPathWhole) {
  fs::path dir = fs::path(scratch("x")).parent_path();
  for (int i = 0; i < 6; ++i) dir /= std::string(100, char('a' + i));
  fs::create_directories(dir);
  const std::string data = (dir / "tank.csv").string();
  ASSERT_GT(data.size(), 600u);
  ASSERT_EQ(run(kTank + " simulate --out " + data + " --duration 1").exitCode, 0);
  const Result r = run(kTank + " paper --runs 1 --out-dir " + scratch("paper") + " --data " + data);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("data: " + data + ", 1001 rows; RMSE over"), std::string::npos) << r.output;
}

// gnuplot runs without a shell and the paths in its script are quoted: an out dir with a quote and a
// space still gets its figures, and one crafted to close the quote runs nothing.
TEST(Paper, PlotsIntoADirectoryWithQuotesAndSpaces) {
  if (run("gnuplot --version").exitCode != 0) GTEST_SKIP() << "gnuplot is not installed";
  const fs::path base = fs::path(scratch("x")).parent_path();
  for (const std::string name : {"it's a dir", "x'; touch pwned; '"}) {
    const fs::path dir = base / name;
    fs::remove_all(dir);
    fs::remove(base / "pwned");
    const Result r = run("cd " + shellQuote(base.string()) + " && " + kTank +
                         " paper --duration 1 --runs 1 --out-dir " + shellQuote(dir.string()));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* file : {"coupled_tank_parameters.png", "coupled_tank_states.png"})
      EXPECT_GT(fs::exists(dir / file) ? fs::file_size(dir / file) : 0u, 1000u) << name << ": " << file << "\n"
                                                                                << r.output;
    EXPECT_FALSE(fs::exists(base / "pwned")) << name << ": the shell ran a command from the path";
  }
}

// ---------------------------------------------------------------------------------------------
// Malformed input: exit code 2 and the line number, never a crash or a partial run.

struct MalformedCase {
  const char* name;
  const char* text;
  const char* lineTag;  // "file:LINE:" expected in the message
};
void PrintTo(const MalformedCase& c, std::ostream* os) { *os << c.name; }

class MalformedCsv : public ::testing::TestWithParam<MalformedCase> {};

TEST_P(MalformedCsv, ExitsWithCodeTwoAndTheLineNumber) {
  const auto& c = GetParam();
  const std::string path = writeFile("bad.csv", c.text);
  const std::string out = scratch("out.csv");
  fs::remove(out);
  for (const std::string& command :
       std::vector<std::string>{kTank + " estimate --filter jukf --data " + path + " --out " + out,
                                kTank + " paper --runs 1 --out-dir " + scratch("paper") + " --data " + path}) {
    const Result r = run(command);
    EXPECT_EQ(r.exitCode, 2) << command << "\n" << r.output;
    EXPECT_NE(r.output.find(path + ":" + c.lineTag + ":"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("usage:"), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(out)) << "no partial output";
}

INSTANTIATE_TEST_SUITE_P(
    Files, MalformedCsv,
    ::testing::Values(MalformedCase{"TruncatedLastRow", "t,y1,y2\n0,0,0\n0.001,1,2\n0.002,1", "4"},
                      MalformedCase{"NotANumber", "t,y1,y2\n0,0,0\n0.001,1,x2\n0.002,1,2\n", "3"},
                      MalformedCase{"TooManyFields", "t,y1,y2\n0,0,0\n0.001,1,2,3\n", "3"},
                      MalformedCase{"MissingColumn", "t,y1,theta1_true\n0,0,6\n", "1"},
                      MalformedCase{"HeaderOnly", "t,y1,y2\n", "2"},
                      MalformedCase{"WrongTimeGrid", "t,y1,y2\n0,0,0\n0.001,1,2\n0.004,1,2\n", "4"},
                      MalformedCase{"BlankLineInside", "t,y1,y2\n0,0,0\n\n0.002,1,2\n", "3"},
                      MalformedCase{"BlankLineBeforeHeader", "\nt,y1,y2\n0,0,0\n", "1"},
                      // The library's reader reads an empty cell as a missing sample (NaN): the programs
                      // need every measurement, so it is refused on its line like a NaN.
                      MalformedCase{"EmptyCell", "t,y1,y2\n0,0,0\n0.001,,2\n0.002,1,2\n", "3"},
                      // Non-finite values: row 1 is not a measurement row of the tank (every 2 steps), so
                      // a NaN there used to be ignored; on row 2 it stopped the run half way.
                      MalformedCase{"NanInUnmeasuredRow", "t,y1,y2\n0,0,0\n0.001,nan,2\n0.002,1,2\n", "3"},
                      MalformedCase{"InfInMeasuredRow", "t,y1,y2\n0,0,0\n0.001,1,2\n0.002,1,inf\n", "4"},
                      MalformedCase{"NanInTime", "t,y1,y2\n0,0,0\nnan,1,2\n", "3"},
                      MalformedCase{"InfInStateTruth",
                                    "t,y1,y2,x1_true,x2_true,theta1_true\n0,0,0,0,0,6\n0.001,1,2,-inf,2,6\n", "3"},
                      MalformedCase{"NanInParameterTruth",
                                    "t,y1,y2,x1_true,x2_true,theta1_true\n0,0,0,0,0,6\n0.001,1,2,1,2,nan\n", "3"}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(MalformedCsv, MissingFileIsReported) {
  const Result r = run(kRobot + " estimate --filter mjukf --data /nonexistent/file.csv --out " + scratch("o.csv"));
  EXPECT_EQ(r.exitCode, 2) << r.output;
  EXPECT_NE(r.output.find("/nonexistent/file.csv"), std::string::npos) << r.output;
}

// ---------------------------------------------------------------------------------------------
// Bad command lines: a usage message and exit code 64.

TEST(CommandLine, UnknownFlagsAndBadValuesGetTheUsage) {
  const std::string data = kData + "/flexible_joint_reference.csv";
  const std::string est = kRobot + " estimate --data " + data + " --out " + scratch("o.csv");
  const std::vector<std::pair<std::string, std::string>> cases{
      {kRobot, ""},
      {kRobot + " fly", "unknown subcommand 'fly'"},
      {est + " --filter mjukf --bogus 1", "unknown flag '--bogus'"},
      {est + " --filter kf", "--filter must be ukf, jukf, mjukf or dual"},
      {est, "--filter is required"},
      {est + " --filter mjukf --every 0", "--every needs an integer >= 1"},
      {est + " --filter mjukf --xi abc", "--xi needs a finite number"},
      {est + " --filter jukf --xi -1", "--xi applies to mjukf only"},
      {est + " --filter dual --xi -1", "--xi applies to mjukf only"},
      {est + " --filter mjukf --ordering prior", "--ordering applies to dual only"},
      {est + " --filter jukf --ordering updated", "--ordering applies to dual only"},
      {est + " --filter ukf --r-theta 1e-2", "--r-theta applies to dual only"},
      {est + " --filter dual --ordering bogus", "--ordering must be prior or updated, not 'bogus'"},
      {est + " --filter dual --ordering", "--ordering needs a value"},
      {est + " --filter dual --r-theta -1", "bad filter setting"},
      {est + " --filter mjukf --theta0 0.1", "--theta0 needs 2 comma-separated numbers"},
      {est + " --filter jukf --r -1", "bad filter setting"},
      {est + " --filter mjukf --every", "--every needs a value"},
      {kTank + " simulate --out " + scratch("s.csv") + " --change-at 5", "no parameter-change scenario"},
      {kTank + " simulate --out " + scratch("s.csv") + " --snr-db -inf", "--snr-db needs a finite number"},
      {kTank + " paper --runs 0", "--runs needs an integer >= 1"},
      {kTank + " paper --change-data x.csv", "unknown flag '--change-data'"},
  };
  for (const auto& [command, message] : cases) {
    const Result r = run(command);
    EXPECT_EQ(r.exitCode, 64) << command << "\n" << r.output;
    EXPECT_NE(r.output.find("usage:"), std::string::npos) << command << "\n" << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << command << "\n" << r.output;
  }
  const Result help = run(kTank + " --help");
  EXPECT_EQ(help.exitCode, 0);
  EXPECT_NE(help.output.find("simulate"), std::string::npos);
  for (const char* text : {"--filter ukf|jukf|mjukf|dual", "--ordering prior|updated", "--r-theta DIAG"})
    EXPECT_NE(help.output.find(text), std::string::npos) << text << "\n" << help.output;
}

// --every is an int in the filter setup: a larger value must be refused, not wrapped (2^32 + 2 ran
// with N = 2, 2^31 became INT_MIN).
TEST(CommandLine, EveryBeyondIntRangeIsRefused) {
  const std::string out = scratch("o.csv");
  fs::remove(out);
  const std::string est =
      kRobot + " estimate --filter mjukf --data " + kData + "/flexible_joint_reference.csv --out " + out;
  for (const char* every : {"4294967298", "2147483648", "99999999999999999999999"}) {
    const Result r = run(est + " --every " + every);
    EXPECT_EQ(r.exitCode, 64) << every << "\n" << r.output;
    EXPECT_NE(r.output.find("--every needs an integer >= 1 and <= 2147483647"), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
