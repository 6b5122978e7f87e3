// mjukf_cascaded_tanks, run as a user runs it on the shipped benchmark data: `identify` end to end
// (the files it writes, the test simulation's CSV, and the JUKF's test RMS it prints, recomputed from
// that CSV as the benchmark defines it), `crosscheck` (the records swapped), and a missing or malformed
// data file refused with exit 2.

#include <cmath>
#include <fstream>
#include <sstream>
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
using mjukf::program_tests::writeFile;

const std::string kProgram = MJUKF_CASCADED_TANKS;
const std::string kData = MJUKF_CASCADED_DATA;

std::vector<std::string> lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> all;
  for (std::string line; std::getline(in, line);) all.push_back(line);
  return all;
}

// The test set's simulation: one row per test sample; the printed RMS is the benchmark's score of
// that simulation (yVal[5..]); the model's fit beats the best linear approximation (0.757 V).
TEST(CascadedTanks, IdentifyWritesTheTestSimulationAndItsScore) {
  const std::string dir = scratch("cascaded_tanks");
  const Result r = run(kProgram + " identify --data " + shellQuote(kData) + " --out-dir " + shellQuote(dir));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  for (const char* name : {"/results.txt", "/test_simulation.csv"})
    EXPECT_TRUE(std::ifstream(dir + name).good()) << name;
  for (const char* filter : {"| JUKF |", "| MJUKF (automatic) |", "| dual UKF |", "| published: NLSS2 | 0.343"})
    EXPECT_NE(readText(dir + "/results.txt").find(filter), std::string::npos) << filter;

  const std::vector<std::string> csv = lines(dir + "/test_simulation.csv");
  ASSERT_EQ(csv.size(), 1u + 1024u);
  EXPECT_EQ(csv[0], "t,u,y_measured,y_simulated");
  double sum = 0;
  for (std::size_t k = 1; k < csv.size(); ++k) {
    std::stringstream row(csv[k]);
    std::string field;
    std::vector<double> values;
    while (std::getline(row, field, ',')) values.push_back(std::stod(field));
    ASSERT_EQ(values.size(), 4u) << csv[k];
    EXPECT_DOUBLE_EQ(values[0], 4.0 * double(k - 1));
    if (k - 1 >= 5) sum += (values[2] - values[3]) * (values[2] - values[3]);
  }
  const double rms = std::sqrt(sum / (1024 - 5));

  const std::string tag = "JUKF test RMS: ";
  const std::size_t at = r.output.find(tag);
  ASSERT_NE(at, std::string::npos) << r.output;
  const double printed = std::stod(r.output.substr(at + tag.size()));
  EXPECT_NEAR(rms, printed, 5e-5) << r.output;  // printed with 4 decimals
  EXPECT_LT(rms, 0.757);
}

// The rule on the records swapped: its table, and the JUKF's RMS on the record it did not see, written
// whole and better than the best linear approximation's 0.757 V.
TEST(CascadedTanks, CrosscheckScoresTheRecordItDidNotIdentifyOn) {
  const std::string dir = scratch("cascaded_tanks_crosscheck");
  const Result r = run(kProgram + " crosscheck --data " + shellQuote(kData) + " --out-dir " + shellQuote(dir));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const std::string report = readText(dir + "/crosscheck.txt");
  for (const char* row : {"| JUKF |", "| MJUKF (automatic) |", "| dual UKF |", "| output-error fit", "- JUKF:"})
    EXPECT_NE(report.find(row), std::string::npos) << row;
  const std::string tag = "JUKF crosscheck RMS: ";
  const std::size_t at = report.find(tag);
  ASSERT_NE(at, std::string::npos) << report;
  const double rms = std::stod(report.substr(at + tag.size()));
  EXPECT_GT(rms, 0.0);
  EXPECT_LT(rms, 0.757);
}

TEST(CascadedTanks, RefusesAMissingOrMalformedFile) {
  const std::string dir = scratch("cascaded_tanks_bad");
  const Result missing =
      run(kProgram + " identify --data " + shellQuote(dir + "/none.csv") + " --out-dir " + shellQuote(dir));
  EXPECT_EQ(missing.exitCode, 2) << missing.output;
  EXPECT_NE(missing.output.find("none.csv"), std::string::npos) << missing.output;

  const std::string bad = writeFile("cascaded_bad.csv", "uEst,uVal,yEst,yVal,Ts\n1,2,3,4,4\n1,2,x,4,\n");
  const Result malformed = run(kProgram + " identify --data " + shellQuote(bad) + " --out-dir " + shellQuote(dir));
  EXPECT_EQ(malformed.exitCode, 2) << malformed.output;
  EXPECT_NE(malformed.output.find(":3:"), std::string::npos) << malformed.output;  // the line

  const std::string columns = writeFile("cascaded_columns.csv", "u,y\n1,2\n");
  const Result wrong = run(kProgram + " identify --data " + shellQuote(columns) + " --out-dir " + shellQuote(dir));
  EXPECT_EQ(wrong.exitCode, 2) << wrong.output;
  EXPECT_NE(wrong.output.find("uEst"), std::string::npos) << wrong.output;

  EXPECT_EQ(run(kProgram + " identify --data " + shellQuote(kData)).exitCode, 64);  // no --out-dir
  EXPECT_EQ(run(kProgram + " fit").exitCode, 64);
  EXPECT_EQ(run(kProgram).exitCode, 64);
}

}  // namespace
