// mjukf_gallery, run as a user runs it: the list of plants, a short study of each plant end to end
// (every filter the baseline of docs/studies.md runs, two seeds), the simulation's absolute noise
// through the measurement with the input of its row, and the flags that do not apply to the gallery.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mjukf/models/thevenin_battery.hpp"
#include "run_program.hpp"

namespace {

using mjukf::program_tests::Result;
using mjukf::program_tests::run;
using mjukf::program_tests::scratch;
using mjukf::program_tests::shellQuote;

const std::string kGallery = MJUKF_GALLERY;

struct GalleryPlant {
  std::string slug;
  std::string duration;  // short runs: long enough for JUKF to settle on seed 1
};

const std::vector<GalleryPlant> kPlants{
    {"dc_motor", "2"}, {"battery", "600"}, {"predator_prey", "30"}, {"heated_block", "200"}, {"drug_infusion", "24"}};

std::vector<std::vector<std::string>> readCsv(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> fields;
    std::stringstream stream(line);
    for (std::string field; std::getline(stream, field, ',');) fields.push_back(field);
    rows.push_back(fields);
  }
  return rows;
}

// Without a plant: the list (exit 64 on stderr), with --help on stdout (exit 0); an unknown plant
// gets the list and exit 64; a plant without a subcommand gets that plant's usage.
TEST(Gallery, ListsItsPlants) {
  for (const auto& [command, code] : {std::pair{kGallery, 64}, std::pair{kGallery + " --help", 0}}) {
    const Result r = run(command);
    EXPECT_EQ(r.exitCode, code) << r.output;
    for (const auto& plant : kPlants) EXPECT_NE(r.output.find(plant.slug), std::string::npos) << r.output;
  }
  const Result unknown = run(kGallery + " tank study");
  EXPECT_EQ(unknown.exitCode, 64);
  EXPECT_NE(unknown.output.find("unknown plant 'tank'"), std::string::npos) << unknown.output;
  const Result usage = run(kGallery + " battery");
  EXPECT_EQ(usage.exitCode, 64);
  EXPECT_NE(usage.output.find("usage: mjukf_gallery battery SUBCOMMAND"), std::string::npos) << usage.output;
}

// Each plant's study with the baseline's filters: one CSV row per seed and filter, a table line per
// filter, and JUKF, the reference that works on every plant, through seed 1 without diverging.
TEST(Gallery, ShortStudyOfEachPlant) {
  for (const auto& plant : kPlants) {
    const std::string dir = scratch(plant.slug);
    const Result r = run(kGallery + " " + plant.slug + " study --seeds 1-2 --filters jukf,mjukf-auto,dual --jobs 2" +
                         " --duration " + plant.duration + " --out-dir " + shellQuote(dir));
    ASSERT_EQ(r.exitCode, 0) << plant.slug << "\n" << r.output;
    for (const char* filter : {"\njukf ", "\nmjukf-auto ", "\ndual "})
      EXPECT_NE(r.output.find(filter), std::string::npos) << plant.slug << "\n" << r.output;
    const auto rows = readCsv(dir + "/" + plant.slug + "_study.csv");
    ASSERT_EQ(rows.size(), 1u + 2 * 3) << plant.slug;
    // seed, filter, scenario; 2 RMSEs; 5; 2 finals; the final NEES of θ̂; the health at the end; the
    // updates from a forced fault to the first alarm; the first alarm, the blocks and the alarmed ones;
    // the final relative error, the largest correlation of the final covariance of θ̂ and its 2 σ; the
    // changes of θ the automatic MJUKF's test found
    ASSERT_EQ(rows[0].size(), 3u + 2 + 5 + 2 + 1 + 1 + 1 + 3 + 2 + 2 + 1) << plant.slug;
    EXPECT_EQ(rows[1][0] + "," + rows[1][1], "1,jukf") << plant.slug;
    EXPECT_EQ(rows[1][5], "0") << plant.slug << ": JUKF diverged on seed 1";
    EXPECT_EQ(rows[1][6], "ok") << plant.slug;
  }
}

// The battery's simulated voltage is OCV(z) − v₁ − R₀ i(t) at the true state of its row plus noise of
// the experiment's 2 mV: the measurement is taken with the input of that row (the current steps at
// whole seconds, so a row's input off by one would leave residuals of R₀ × 2.5 A = 0.125 V).
TEST(Gallery, BatteryNoiseIsAbsoluteAndTheMeasurementTakesTheRowsInput) {
  const std::string data = scratch("battery.csv");
  const Result r = run(kGallery + " battery simulate --out " + shellQuote(data));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("noise std 0.002"), std::string::npos) << r.output;
  const mjukf::models::TheveninBattery<double> model;
  const auto rows = readCsv(data);
  ASSERT_EQ(rows.size(), 3602u);
  ASSERT_EQ(rows[0], (std::vector<std::string>{"t", "y1", "x1_true", "x2_true", "theta1_true", "theta2_true"}));
  double sum = 0, squares = 0, largest = 0;
  for (std::size_t k = 1; k < rows.size(); ++k) {
    const double t = std::stod(rows[k][0]);
    const mjukf::models::TheveninBattery<double>::State x(std::stod(rows[k][2]), std::stod(rows[k][3]));
    const double residual = std::stod(rows[k][1]) - model.measurement(x, model.input(t), model.trueParameters())(0);
    sum += residual;
    squares += residual * residual;
    largest = std::max(largest, std::abs(residual));
  }
  const double n = double(rows.size() - 1);
  const double sd = std::sqrt(squares / n - (sum / n) * (sum / n));
  EXPECT_NEAR(sd, 0.002, 0.0002);  // 3601 draws: the sample sd is within 10% far beyond 4 sigma
  EXPECT_LT(largest, 0.002 * 6);
}

// The gallery's noise is absolute, so --snr-db is refused; `estimate --filter mjukf` runs the automatic
// preset (mjukf and mjukf-auto are the same on the gallery).
TEST(Gallery, SnrIsRefusedAndMjukfIsTheAutomaticPreset) {
  const Result snr = run(kGallery + " heated_block simulate --snr-db 20 --out " + shellQuote(scratch("x.csv")));
  EXPECT_EQ(snr.exitCode, 64) << snr.output;
  EXPECT_NE(snr.output.find("--snr-db"), std::string::npos) << snr.output;

  const std::string dir = scratch("study");
  const Result study = run(kGallery + " drug_infusion study --seeds 1 --filters mjukf,mjukf-auto --duration 12" +
                           " --out-dir " + shellQuote(dir));
  ASSERT_EQ(study.exitCode, 0) << study.output;
  auto rows = readCsv(dir + "/drug_infusion_study.csv");
  ASSERT_EQ(rows.size(), 3u);
  rows[1][1] = rows[2][1] = "";  // the filter's name is all that differs
  EXPECT_EQ(rows[1], rows[2]);
}

// A forced fault (study --scenarios small-q): the DC motor's JUKF with Q ten thousand times too small
// ends far from the truth, and the health monitor says so in its first block of 50 updates, the delay
// column counting from the fault (at the start) to that first alarm; none is unflagged.
TEST(Gallery, AForcedFaultIsFlaggedInTheFirstBlock) {
  const std::string dir = scratch("forced");
  const Result r =
      run(kGallery + " dc_motor study --seeds 1-3 --filters jukf --scenarios small-q --out-dir " + shellQuote(dir));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto line = r.output.find("\njukf ");
  ASSERT_NE(line, std::string::npos) << r.output;
  const std::string row = r.output.substr(line + 1, r.output.find('\n', line + 1) - line - 1);
  EXPECT_NE(row.find(" 3/3      3/3      0 "), std::string::npos) << row;  // diverged, alarm, unflagged
  EXPECT_NE(row.find("fault to first alarm, diverged runs: median 49 [49, 49] updates"), std::string::npos) << row;
  const auto rows = readCsv(dir + "/dc_motor_study.csv");
  ASSERT_EQ(rows.size(), 4u);
  const auto column = [&](const std::string& name) {
    return std::size_t(std::find(rows[0].begin(), rows[0].end(), name) - rows[0].begin());
  };
  ASSERT_LT(column("updates_to_alarm"), rows[0].size());
  ASSERT_LT(column("alarmed_blocks"), rows[0].size());
  for (std::size_t k = 1; k < rows.size(); ++k) {
    EXPECT_EQ(rows[k][column("updates_to_alarm")], "49") << k;
    EXPECT_EQ(rows[k][column("first_alarm")], rows[k][column("health")]) << k;
    EXPECT_NE(rows[k][column("alarmed_blocks")], "0") << k;
  }
}

// The dual UKF's σ of θ̂ is honest where the plant is the model it assumes (study --scenarios matched:
// the data drawn with the filter's own Q, Q_θ and R, one time update per measurement interval): on the
// DC motor measured by its angle alone (one output, two parameters of opposite-sign sensitivity), the
// mean NEES of the final θ̂ over 50 seeds lies in the 95 % band of χ²(100) / 50, [74.22, 129.56] / 50
// (docs/studies.md, "The plant as the filters model it"), and no run diverges. The seeds' noise is
// libstdc++'s std::normal_distribution: with another standard library's draws, a correct filter falls
// outside a 95 % band on one seed set in twenty.
TEST(Gallery, TheDualsSigmaIsHonestWhereThePlantIsItsModel) {
  const std::string dir = scratch("matched");
  const Result r =
      run(kGallery + " dc_motor study --seeds 1-50 --filters dual --scenarios matched --out-dir " + shellQuote(dir));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto rows = readCsv(dir + "/dc_motor_study.csv");
  ASSERT_EQ(rows.size(), 51u);
  const auto column = [&](const std::string& name) {
    return std::size_t(std::find(rows[0].begin(), rows[0].end(), name) - rows[0].begin());
  };
  ASSERT_LT(column("nees"), rows[0].size());
  double sum = 0;
  for (std::size_t k = 1; k < rows.size(); ++k) {
    EXPECT_EQ(rows[k][column("diverged")], "0") << k;
    sum += std::stod(rows[k][column("nees")]);
  }
  const double mean = sum / 50;
  EXPECT_GE(mean, 74.22 / 50);
  EXPECT_LE(mean, 129.56 / 50);
}

}  // namespace

// `true-start` starts every filter at the truth, `static` at the first guess: after the block's first
// reading (0.1 s), which moves G_ba by about 1e-8 of itself (the slow temperature hardly changes in that
// time), each filter's G_ba is still where the scenario started it: 10 W/K (the truth) or 5 (the guess).
TEST(Gallery, TrueStartBeginsEveryFilterAtTheTruth) {
  const std::string dir = scratch("true_start");
  const Result r = run(kGallery + " heated_block study --seeds 1 --filters jukf,mjukf-auto,dual --jobs 1" +
                       " --scenarios static,true-start --duration 0.1 --out-dir " + shellQuote(dir));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto rows = readCsv(dir + "/heated_block_study.csv");
  ASSERT_EQ(rows.size(), 1u + 2 * 3);
  const std::size_t finalSecond = 3 + 2 + 5 + 1;  // final_G_ba
  ASSERT_EQ(rows[0][finalSecond], "final_G_ba");
  for (std::size_t row = 1; row < rows.size(); ++row) {
    const bool truthStart = rows[row][2] == "true-start";
    const double expected = truthStart ? 10.0 : 5.0;
    EXPECT_NEAR(std::stod(rows[row][finalSecond]), expected, 1e-3 * expected) << rows[row][1] << " " << rows[row][2];
  }
}
