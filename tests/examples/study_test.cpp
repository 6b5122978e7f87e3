// The `study` subcommand and the 2019 systems' programs, run as a user runs them: a study's CSV does
// not depend on --jobs, its rows follow the seeds, bad --seeds / --filters / --out-dir get the usage
// (exit 64) naming the flag, and the Van der Pol and Lorenz programs simulate and estimate.

#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "run_program.hpp"

namespace {

using mjukf::program_tests::readText;
using mjukf::program_tests::Result;
using mjukf::program_tests::run;
using mjukf::program_tests::scratch;
using mjukf::program_tests::shellQuote;

const std::string kTank = MJUKF_COUPLED_TANK;
const std::string kRobot = MJUKF_FLEXIBLE_JOINT;
const std::string kVanDerPol = MJUKF_VAN_DER_POL;
const std::string kLorenz = MJUKF_LORENZ;

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> result;
  std::string::size_type start = 0;
  for (auto end = text.find('\n'); end != std::string::npos; start = end + 1, end = text.find('\n', start))
    result.push_back(text.substr(start, end - start));
  return result;
}

// Runs `study` with --jobs 1 and --jobs 2 into two directories and returns both CSVs.
std::pair<std::string, std::string> studyWithOneAndTwoJobs(const std::string& program, const std::string& slug,
                                                           const std::string& flags) {
  std::string csv[2];
  for (int jobs = 1; jobs <= 2; ++jobs) {
    const std::string dir = scratch("jobs" + std::to_string(jobs));
    const Result r =
        run(program + " study " + flags + " --jobs " + std::to_string(jobs) + " --out-dir " + shellQuote(dir));
    EXPECT_EQ(r.exitCode, 0) << r.output;
    csv[jobs - 1] = readText(dir + "/" + slug + "_study.csv");
  }
  return {csv[0], csv[1]};
}

// The robot's two scenarios on 1 s runs: four seeds × two filters × two scenarios, the same bytes with
// one and two jobs, one row per scenario × seed × filter in that order, and distinct seeds giving
// distinct RMSEs (each run draws its own noise).
TEST(Study, CsvIsTheSameForOneAndTwoJobs) {
  const auto [one, two] = studyWithOneAndTwoJobs(
      kRobot, "flexible_joint", "--seeds 3,1-2,9 --filters jukf,mjukf --scenarios static,change --duration 1");
  EXPECT_EQ(one, two);
  const auto rows = lines(one);
  ASSERT_EQ(rows.size(), 1u + 4 * 2 * 2);
  EXPECT_EQ(rows[0].rfind("seed,filter,scenario,rmse_K_tau,rmse_m,diverged,status,", 0), 0u) << rows[0];
  const std::vector<std::string> order{"3,jukf,static,",  "3,mjukf,static,", "1,jukf,static,",
                                       "1,mjukf,static,", "2,jukf,static,",  "2,mjukf,static,",
                                       "9,jukf,static,",  "9,mjukf,static,", "3,jukf,change,"};
  for (std::size_t i = 0; i < order.size(); ++i) EXPECT_EQ(rows[i + 1].rfind(order[i], 0), 0u) << rows[i + 1];
  std::set<std::string> jukfRmses;  // fields 4 and 5 (rmse_K_tau, rmse_m) of the static JUKF rows
  for (std::size_t i = 1; i <= 8; i += 2)
    jukfRmses.insert(std::regex_replace(rows[i], std::regex("^([^,]*,){3}([^,]*,[^,]*),.*$"), "$2"));
  EXPECT_EQ(jukfRmses.size(), 4u) << one;
}

// The 2019 systems through the same path, with the full 100 s runs (they are short).
TEST(Study, VanDerPolCsvIsTheSameForOneAndTwoJobs) {
  const auto [one, two] = studyWithOneAndTwoJobs(kVanDerPol, "van_der_pol", "--seeds 1-5 --filters jukf,mjukf,dual");
  EXPECT_EQ(one, two);
  EXPECT_EQ(lines(one).size(), 1u + 5 * 3);
}

// MJUKF automatic is offered (MJUKF's settings have the automatic modes) and is the default's third
// filter; on Van der Pol it runs and is scored like the others, its final θ̂ against its own covariance
// (the automatic modes follow it; the paper's hand-tuned preset does not, and shows "-").
TEST(Study, OffersMjukfAutomaticByDefault) {
  const std::string dir = scratch("out");
  const Result r = run(kVanDerPol + " study --seeds 1-2 --out-dir " + shellQuote(dir));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_TRUE(std::regex_search(
      r.output,
      std::regex("\nmjukf-auto +([-0-9.e]+ \\+- [-0-9.e]+ +[-0-9.e]+|- +-) +[0-2]/2 +[0-2]/2 +[0-2] +[0-2]/[0-2] +"
                 "[-0-9.e]+ \\[[-0-9.e]+, [-0-9.e]+\\]\n")))
      << r.output;
  EXPECT_NE(run(kVanDerPol + " --help").output.find("mjukf-auto"), std::string::npos);
}

// The table on stdout names every filter with its diverged count, the runs that ended with a health
// alarm, those that diverged without one and the alarms on accurate runs, and the files are written.
TEST(Study, PrintsTheTableAndWritesItsFiles) {
  const std::string dir = scratch("out");
  const Result r = run(kTank + " study --seeds 1-3 --jobs 2 --duration 5 --out-dir " + shellQuote(dir));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_TRUE(std::regex_search(r.output, std::regex("\njukf +[-0-9.e]+ \\+- [-0-9.e]+ +[-0-9.e]+ +0/3 +[0-3]/3 +0 "
                                                     "+[0-3]/[0-3] +[-0-9.e]+ \\[[-0-9.e]+, [-0-9.e]+\\]\n")))
      << r.output;
  EXPECT_TRUE(std::regex_search(
      r.output, std::regex("\nmjukf +[-0-9.e]+ \\+- [-0-9.e]+ +[-0-9.e]+ +0/3 +[0-3]/3 +0 +[0-3]/[0-3] +-\n")))
      << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir + "/coupled_tank_study.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/coupled_tank_study_table.txt"));
  if (run("gnuplot --version").exitCode == 0) {
    EXPECT_TRUE(std::filesystem::exists(dir + "/coupled_tank_study_static.png"));
  }
}

// Bad command lines: the usage (exit 64) and a message naming the flag.
TEST(Study, BadSeedsFiltersAndOutputDirectoryGetTheUsage) {
  const std::string file = scratch("a-file");
  std::ofstream(file) << "not a directory\n";
  const std::string out = " --out-dir " + shellQuote(scratch("unused"));
  const std::vector<std::pair<std::string, std::string>> cases{
      {kTank + " study --seeds 5-3" + out, "--seeds"},  // a range that runs backwards: no seed
      {kTank + " study --seeds ''" + out, "--seeds"},   // zero seeds
      {kTank + " study --seeds 1-x" + out, "--seeds"},
      {kTank + " study --seeds 1,2,1" + out, "--seeds"},
      {kTank + " study --seeds 1, " + out, "--seeds"},
      {kTank + " study --seeds 1-99999999999" + out, "--seeds"},
      {kTank + " study --filters jukf,nope" + out, "--filters"},
      {kTank + " study --scenarios change" + out, "--scenarios"},  // the tank has no parameter change
      {kTank + " study --jobs 0" + out, "--jobs"},
      {kTank + " study --out-dir " + shellQuote(file + "/sub"), "--out-dir"},  // under a regular file
  };
  for (const auto& [command, flag] : cases) {
    const Result r = run(command);
    EXPECT_EQ(r.exitCode, 64) << command << "\n" << r.output;
    EXPECT_NE(r.output.find(flag), std::string::npos) << command << "\n" << r.output;
    EXPECT_NE(r.output.find("usage:"), std::string::npos) << command << "\n" << r.output;
  }
}

// The new programs: simulate, then estimate with the 2019 settings; the run goes through and prints a
// finite RMSE for every parameter.
TEST(Systems2019, SimulateThenEstimate) {
  for (const auto& [program, parameters] : {std::pair{kVanDerPol, 1}, std::pair{kLorenz, 3}}) {
    const std::string data = scratch("data.csv"), out = scratch("estimate.csv");
    const Result simulated = run(program + " simulate --duration 20 --out " + shellQuote(data));
    ASSERT_EQ(simulated.exitCode, 0) << simulated.output;
    EXPECT_NE(simulated.output.find("noise std 0.1 |x_i|"), std::string::npos) << simulated.output;
    for (const char* filter : {"jukf", "mjukf"}) {
      const Result r =
          run(program + " estimate --filter " + filter + " --data " + shellQuote(data) + " --out " + shellQuote(out));
      ASSERT_EQ(r.exitCode, 0) << program << " " << filter << "\n" << r.output;
      for (int i = 1; i <= parameters; ++i)
        EXPECT_TRUE(std::regex_search(r.output, std::regex("rmse_theta" + std::to_string(i) + ": [0-9]"))) << r.output;
    }
    // Their noise is relative: there is no SNR to set.
    EXPECT_EQ(run(program + " simulate --snr-db 20 --out " + shellQuote(data)).exitCode, 64);
  }
}

}  // namespace
