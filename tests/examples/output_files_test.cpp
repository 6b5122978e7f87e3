// The example programs' output files are whole or absent (examples/support/common/atomic_file.hpp): a
// run that fails on a full disk, is interrupted by SIGINT or SIGTERM, has a filter refuse a step, or
// has gnuplot fail leaves every previous output as it was (the same inode and bytes) and no partial or
// temporary file; its error goes to stderr with the documented exit code. And `estimate` refuses a
// data file whose columns are not the plant's, naming them.
//
// A full disk without root: the shell's `ulimit -f` sets RLIMIT_FSIZE for the program it then starts,
// so every write beyond the limit fails with EFBIG (the programs ignore SIGXFSZ, which would kill them
// instead), and gnuplot, which gets SIGXFSZ back at its default, is killed by it. `--out /dev/full`
// fails every write with ENOSPC.

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "run_program.hpp"

namespace {

namespace fs = std::filesystem;
using namespace mjukf::program_tests;  // run, runSeparately, start, scratch, listing, …

const std::string kTank = MJUKF_COUPLED_TANK;
const std::string kRobot = MJUKF_FLEXIBLE_JOINT;

// Every entry of `dir`, hidden ones included, with its inode and bytes: a file replaced by one of the
// same bytes still shows.
using Snapshot = std::map<std::string, std::pair<ino_t, std::string>>;
Snapshot snapshot(const fs::path& dir) {
  Snapshot entries;
  for (const auto& [name, bytes] : listing(dir)) {
    struct stat status {};
    ::stat((dir / name).c_str(), &status);
    entries[name] = {status.st_ino, bytes};
  }
  return entries;
}

std::string names(const Snapshot& entries) {
  std::string text;
  for (const auto& entry : entries) text += " " + entry.first;
  return text;
}

bool haveGnuplot() { return run("gnuplot --version").exitCode == 0; }

// ---------------------------------------------------------------------------------------------
// A full disk: exit 1, the file named, nothing replaced, nothing left.

struct FullDiskCase {
  const char* name;
  std::string previous;  // commands that make the previous outputs in DIR
  std::string failing;   // the run that must fail, under `ulimit -f`
  const char* limit;     // in 512-byte blocks (dash)
  const char* file;      // the file the message names
  bool needsGnuplot;
};
void PrintTo(const FullDiskCase& c, std::ostream* os) { *os << c.name; }

class FullDisk : public ::testing::TestWithParam<FullDiskCase> {};

TEST_P(FullDisk, LeavesEveryPreviousFileAndNoTemporary) {
  const auto& c = GetParam();
  if (c.needsGnuplot && !haveGnuplot()) GTEST_SKIP() << "gnuplot is not installed";
  const fs::path dir = scratch("out");
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto expand = [&](std::string command) {
    for (std::size_t at; (at = command.find("DIR")) != std::string::npos;) command.replace(at, 3, dir.string());
    return command;
  };
  const Result previous = run(expand(c.previous));
  ASSERT_EQ(previous.exitCode, 0) << previous.output;
  const auto before = snapshot(dir);
  ASSERT_GE(before.size(), 1u);

  // stderr into the pipe, not a file: under the limit a file would take none of it.
  const Result r = run(std::string("ulimit -f ") + c.limit + " && " + expand(c.failing));
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find((dir / c.file).string() + ": "), std::string::npos) << r.output;
  EXPECT_EQ(snapshot(dir), before) << "before:" << names(before) << "\nafter: " << names(snapshot(dir)) << "\n"
                                   << r.output;
}

INSTANTIATE_TEST_SUITE_P(
    Subcommands, FullDisk,
    ::testing::Values(FullDiskCase{"Simulate", kTank + " simulate --out DIR/sim.csv --duration 1 --seed 1",
                                   kTank + " simulate --out DIR/sim.csv --duration 2 --seed 2", "0", "sim.csv", false},
                      // Half the limit is the header and a few rows: the file is cut in the middle, not left empty.
                      FullDiskCase{"SimulateCutMidway", kRobot + " simulate --out DIR/sim.csv --duration 1",
                                   kRobot + " simulate --out DIR/sim.csv --duration 3", "64", "sim.csv", false},
                      FullDiskCase{"Estimate",
                                   kTank + " simulate --out DIR/data.csv --duration 1 && " + kTank +
                                       " estimate --filter jukf --data DIR/data.csv --out DIR/est.csv",
                                   kTank + " estimate --filter mjukf --data DIR/data.csv --out DIR/est.csv", "0",
                                   "est.csv", false},
                      FullDiskCase{"Paper", kTank + " paper --duration 1 --runs 1 --out-dir DIR",
                                   kTank + " paper --duration 2 --runs 1 --out-dir DIR", "0", "coupled_tank_data.csv",
                                   false},
                      FullDiskCase{"StudyCsv", kTank + " study --seeds 1-2 --duration 1 --jobs 1 --out-dir DIR",
                                   kTank + " study --seeds 1-3 --duration 1 --jobs 1 --out-dir DIR", "0",
                                   "coupled_tank_study.csv", false},
                      // The CSV, table and script fit in 4 KiB, the PNG does not: gnuplot is stopped writing it.
                      FullDiskCase{"StudyPng", kTank + " study --seeds 1-2 --duration 1 --jobs 1 --out-dir DIR",
                                   kTank + " study --seeds 1-3 --duration 1 --jobs 1 --out-dir DIR", "8",
                                   "coupled_tank_study_static.png", true}),
    [](const auto& info) { return std::string(info.param.name); });

// A device is written in place (there is nothing to rename over): a failed write is still an error.
TEST(DeviceOutput, DevFullIsAnErrorNamingIt) {
  const Result r = runSeparately(kTank + " simulate --out /dev/full --duration 1", scratch("errors"));
  EXPECT_EQ(r.exitCode, 1) << r.output << r.errors;
  EXPECT_NE(r.errors.find("/dev/full: writing the file failed"), std::string::npos) << r.errors;
  EXPECT_EQ(r.output.find("simulated"), std::string::npos) << r.output;
}

// ---------------------------------------------------------------------------------------------
// Interrupted: a study stopped while it runs exits 128 + the signal and leaves the previous study.

// Waits up to `seconds` for `pid` to exit; its exit code, or -2 (after killing it) when it did not.
int waitWithin(pid_t pid, double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  for (;;) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return -2;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

// Whether `dir` holds a temporary of this program (a hidden name with ".tmp-").
bool hasTemporary(const fs::path& dir) {
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name[0] == '.' && name.find(".tmp-") != std::string::npos) return true;
  }
  return false;
}

class Interrupted : public ::testing::TestWithParam<int> {};

TEST_P(Interrupted, StudyLeavesThePreviousStudy) {
  const int signal = GetParam();
  const fs::path dir = scratch("study");
  fs::remove_all(dir);
  const Result previous = run(kTank + " study --seeds 1-2 --duration 1 --out-dir " + shellQuote(dir.string()));
  ASSERT_EQ(previous.exitCode, 0) << previous.output;
  const auto before = snapshot(dir);

  // 5000 runs of 200 s: minutes of work, stopped once the study has made its temporaries.
  const std::string log = scratch("log");
  const pid_t pid = start({kTank, "study", "--seeds", "1-5000", "--out-dir", dir.string()}, log);
  ASSERT_GT(pid, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!hasTemporary(dir) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_TRUE(hasTemporary(dir)) << names(snapshot(dir));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // well into the runs
  kill(pid, signal);
  const int exitCode = waitWithin(pid, 60);
  const std::string output = readText(log);
  EXPECT_EQ(exitCode, 128 + signal) << output;
  EXPECT_NE(output.find(signal == SIGINT ? "interrupted (SIGINT)" : "interrupted (SIGTERM)"), std::string::npos)
      << output;
  EXPECT_EQ(snapshot(dir), before) << "after:" << names(snapshot(dir)) << "\n" << output;
}

INSTANTIATE_TEST_SUITE_P(Signals, Interrupted, ::testing::Values(SIGINT, SIGTERM),
                         [](const auto& info) { return info.param == SIGINT ? "Sigint" : "Sigterm"; });

// ---------------------------------------------------------------------------------------------
// A refused step: exit 1, the explanation on stderr, no estimates file (not rows 0…k−1 of one).

TEST(RefusedStep, EstimateWritesNothing) {
  const fs::path dir = scratch("out");
  fs::remove_all(dir);
  fs::create_directories(dir);
  // A measurement of 1e300 on row 2 (a measurement row of the tank) makes the update overflow.
  std::ofstream(dir / "huge.csv") << "t,y1,y2\n0,0,0\n0.001,1,2\n0.002,1e300,2\n0.003,1,2\n0.004,1,2\n";
  const std::string out = (dir / "est.csv").string();
  const Result good = run(kTank + " simulate --out " + (dir / "good.csv").string() + " --duration 1 && " + kTank +
                          " estimate --filter jukf --data " + (dir / "good.csv").string() + " --out " + out);
  ASSERT_EQ(good.exitCode, 0) << good.output;
  const auto before = snapshot(dir);
  for (const char* filter : {"ukf", "jukf", "mjukf", "dual"}) {
    const Result r = runSeparately(
        kTank + " estimate --filter " + filter + " --data " + (dir / "huge.csv").string() + " --out " + out,
        scratch("errors"));
    EXPECT_EQ(r.exitCode, 1) << filter << "\n" << r.output << r.errors;
    EXPECT_NE(r.errors.find("the filter refused the step to row 2 (t = 0.002 s)"), std::string::npos) << r.errors;
    EXPECT_NE(r.errors.find(out + " not written"), std::string::npos) << r.errors;
    EXPECT_EQ(r.output.find("refused"), std::string::npos) << r.output;
    EXPECT_EQ(snapshot(dir), before) << filter << ": after:" << names(snapshot(dir));
  }
}

// ---------------------------------------------------------------------------------------------
// gnuplot fails: no PNG, a message naming it, and no other file of the run. A stand-in gnuplot on the
// PATH passes the programs' probe and then fails on the figure: with an exit status, or by leaving a
// PNG cut short and exiting with 0.

TEST(GnuplotFails, NothingOfTheRunIsWritten) {
  const fs::path dir = scratch("study"), bin = scratch("bin");
  fs::remove_all(dir);
  fs::create_directories(bin);
  const Result previous = run(kTank + " study --seeds 1-2 --duration 1 --out-dir " + shellQuote(dir.string()));
  ASSERT_EQ(previous.exitCode, 0) << previous.output;
  const auto before = snapshot(dir);
  const std::string probe = "#!/bin/sh\n[ \"$1\" = -e ] && exit 0\n";
  const std::vector<std::pair<std::string, std::string>> gnuplots{
      {probe + "echo 'line 3: bad script' >&2\nexit 1\n", "gnuplot failed (exit status 1)"},
      {probe + "out=$(sed -n \"s/^set output '\\(.*\\)'$/\\1/p\" \"$1\")\nprintf '\\211PNG\\r\\n\\032\\n' > \"$out\"\n",
       "gnuplot left an incomplete PNG"}};
  for (const auto& [script, message] : gnuplots) {
    std::ofstream(bin / "gnuplot") << script;
    fs::permissions(bin / "gnuplot", fs::perms::owner_all);
    const Result r = runSeparately("PATH=" + shellQuote(bin.string()) + ":\"$PATH\" " + kTank +
                                       " study --seeds 1-3 --duration 1 --out-dir " + shellQuote(dir.string()),
                                   scratch("errors"));
    EXPECT_EQ(r.exitCode, 1) << r.output << r.errors;
    EXPECT_NE(r.errors.find((dir / "coupled_tank_study_static.png").string() + ": " + message), std::string::npos)
        << r.errors;
    EXPECT_EQ(snapshot(dir), before) << "after:" << names(snapshot(dir)) << "\n" << r.errors;
  }
}

// ---------------------------------------------------------------------------------------------
// A data file of another plant: exit 2, the columns expected, found, missing and not the plant's.

TEST(WrongPlant, DataFileIsRefusedNamingTheColumns) {
  const std::string robot = scratch("robot.csv"), tank = scratch("tank.csv"), out = scratch("est.csv");
  ASSERT_EQ(run(kRobot + " simulate --out " + robot + " --duration 0.1").exitCode, 0);
  ASSERT_EQ(run(kTank + " simulate --out " + tank + " --duration 0.1").exitCode, 0);
  fs::remove(out);
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases{
      {kTank + " estimate --filter jukf --data " + robot + " --out " + out,
       {robot + ":1: the columns do not match the plant (Coupled tank)",
        "expected: t, y1, y2 [x1_true, x2_true] [theta1_true]",
        "found:    t, y1, y2, y3, y4, x1_true, x2_true, x3_true, x4_true, theta1_true, theta2_true",
        "not the plant's: y3, y4, x3_true, x4_true, theta2_true"}},
      {kRobot + " estimate --filter mjukf --data " + tank + " --out " + out,
       {tank + ":1: the columns do not match the plant (Flexible-joint robot)",
        "expected: t, y1, y2, y3, y4 [x1_true, x2_true, x3_true, x4_true] [theta1_true, theta2_true]",
        "found:    t, y1, y2, x1_true, x2_true, theta1_true", "missing:  y3, y4, x3_true, x4_true, theta2_true"}},
      {kTank + " paper --runs 1 --out-dir " + scratch("paper") + " --data " + robot,
       {"not the plant's: y3, y4, x3_true, x4_true, theta2_true"}},
  };
  for (const auto& [command, texts] : cases) {
    const Result r = runSeparately(command, scratch("errors"));
    EXPECT_EQ(r.exitCode, 2) << command << "\n" << r.output << r.errors;
    for (const auto& text : texts) EXPECT_NE(r.errors.find(text), std::string::npos) << text << "\n" << r.errors;
    EXPECT_EQ(r.output, "") << command;
  }
  EXPECT_FALSE(fs::exists(out));
  // Its own file, and one without the truth columns, are the tank's.
  EXPECT_EQ(run(kTank + " estimate --filter jukf --data " + tank + " --out " + out).exitCode, 0);
  std::ofstream(scratch("bare.csv")) << "t,y2,y1\n0,0,0\n0.001,1,2\n";
  EXPECT_EQ(run(kTank + " estimate --filter jukf --data " + scratch("bare.csv") + " --out " + out).exitCode, 0);
  // A column the plant does not have is refused, even beside all that it does.
  std::ofstream(scratch("extra.csv")) << "t,y1,y2,u1\n0,0,0,1\n0.001,1,2,1\n";
  const Result extra = run(kTank + " estimate --filter jukf --data " + scratch("extra.csv") + " --out " + out);
  EXPECT_EQ(extra.exitCode, 2) << extra.output;
  EXPECT_NE(extra.output.find("not the plant's: u1"), std::string::npos) << extra.output;
}

}  // namespace
