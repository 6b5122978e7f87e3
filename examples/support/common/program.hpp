#pragma once

// main() of an example program: picks the subcommand, turns every error into a message on stderr and an
// exit code (cli.hpp) instead of a crash, and has signals stop it cleanly (interrupt.hpp).

#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "common/cli.hpp"
#include "common/commands.hpp"
#include "common/csv.hpp"
#include "common/csv_writer.hpp"
#include "common/interrupt.hpp"
#include "common/paper_command.hpp"
#include "common/study_command.hpp"

namespace mjukf::examples {

template <class Plant>
void printUsage(std::ostream& out) {
  const bool change = Plant::parameterChange().has_value();
  constexpr bool snrNoise = hasSnrNoise<typename Plant::Experiment>;
  out << "usage: " << Plant::program << " SUBCOMMAND [--flag value ...]   (" << Plant::title << ")\n"
      << "\n"
      << "  simulate --out FILE [--duration S] [--seed N]" << (snrNoise ? " [--snr-db DB]" : "")
      << (change ? " [--change-at T]" : "") << "\n"
      << "      Simulates the plant (" << Plant::simulation << ") and writes\n"
      << "      t, y1..ym, x1_true..xn_true, theta1_true..thetap_true, one row per step.\n"
      << (change ? "      --change-at T runs the parameter-change scenario (30 s unless --duration).\n" : "") << "\n"
      << "  estimate --filter ukf|jukf|mjukf|dual --data FILE --out FILE [settings]\n"
      << "      Runs a filter with the preset settings and schedule over the measurements y1..ym of FILE and\n"
      << "      writes t, x1..xn, theta1..thetap, one row per data row; prints the parameter RMSEs and\n"
      << "      loop_seconds. dual is the dual UKF with the library's settings (the paper runs none).\n"
      << "      Settings (diagonals take one number or a comma-separated list):\n"
      << "      --every N  --step H  --rmse-from ROW  --x0 LIST  --theta0 LIST  --alpha A  --beta B  --kappa K\n"
      << "      --p0 DIAG  --q DIAG  --r DIAG (dual: of its state filter, alpha, beta, kappa too);\n"
      << "      mjukf only: --xi X|LIST (one for every parameter, or one each)  --p-theta LIST  --transform LIST "
         "(row-major);\n"
      << "      dual only: --ordering prior|updated (the state's time update with the prior or the corrected\n"
      << "      parameters; default prior)  --r-theta DIAG (added to the parameter filter's observation noise)\n"
      << "\n";
  if constexpr (hasPaperTable<Plant>)
    out << "  paper [--data FILE] [--out-dir DIR] " << (change ? "[--change-data FILE] " : "")
        << "[--runs N] [--duration S] [--seed N]\n"
        << "      JUKF and MJUKF as in the paper, and the dual UKF, on a fresh simulation (or FILE): the paper's\n"
        << "      table next to ours (time: median of N = 20 runs), CSV files and PNG plots in DIR (default\n"
        << "      paper_" << Plant::slug << ").\n"
        << "      --duration S is the length of the simulated runs (refused when every data set is a file).\n"
        << "\n";
  out << "  study [--seeds LIST] [--filters LIST] [--scenarios LIST] [--jobs N] [--out-dir DIR] [--duration S]\n"
      << "      The filters over many noise draws, one simulation per seed (default 1-20; ranges and lists such\n"
      << "      as 1-100 or 1,5,9-12), --jobs threads (default: every core; the results do not depend on it).\n"
      << "      Filters: jukf, mjukf, dual"
      << (detail::studyFilters<typename Plant::Experiment::Model>().size() > 3 ? ", mjukf-auto" : "")
      << " (default jukf,mjukf"
      << (detail::studyFilters<typename Plant::Experiment::Model>().size() > 3 ? ",mjukf-auto" : "") << "). Writes DIR/"
      << Plant::slug << "_study.csv\n"
      << "      (one row per seed x filter: RMSEs, diverged, status), a table of mean +- sd and median per filter\n"
      << "      and a box plot per scenario (default DIR study_" << Plant::slug << "). docs/studies.md.\n"
      << "      Scenarios (default static): static" << (change ? ", change (the parameter change)" : "")
      << ", and faults forced on\n"
      << "      the filters: jump (every parameter x1.25 halfway, which constant-parameter presets cannot follow),\n"
      << "      sensor-gain (the data's y x1.1), small-q (every filter's Q of the state x1e-4); matched, the\n"
      << "      plant drawn with the noise the filters assume (the dual UKF's Q, Q_theta and R, given to every "
         "filter);\n"
      << "      and true-start, the static data with every filter started at the true state and parameters.\n"
      << "\n"
      << "Output files are written under temporary names and put in place only when the whole run has\n"
      << "succeeded: a run that fails or is stopped replaces nothing and leaves no partial file.\n"
      << "exit codes: 0 ok; 1 the run failed (a filter refused a step, a file could not be written, gnuplot\n"
      << "failed); 2 malformed input file, or one whose columns are not the plant's; 64 bad command line;\n"
      << "128 + N stopped by signal N (130 SIGINT, 143 SIGTERM, 129 SIGHUP). Errors go to stderr.\n";
}

template <class Plant>
int runProgram(int argc, char** argv) {
  const std::vector<std::string> words(argv + 1, argv + argc);
  if (words.empty() || words[0] == "--help" || words[0] == "-h" || words[0] == "help") {
    printUsage<Plant>(words.empty() ? std::cerr : std::cout);
    return words.empty() ? kExitUsage : kExitOk;
  }
  const std::string& command = words[0];
  const std::vector<std::string> flags(words.begin() + 1, words.end());
  handleInterrupts(Plant::program);
  try {
    if (command == "simulate") return simulateCommand<Plant>(flags);
    if (command == "estimate") return estimateCommand<Plant>(flags);
    if (command == "study") return studyCommand<Plant>(flags);
    if constexpr (hasPaperTable<Plant>)
      if (command == "paper") return paperCommand<Plant>(flags);
    throw UsageError("unknown subcommand '" + command + "'");
  } catch (const UsageError& e) {
    std::cerr << Plant::program << ": " << e.what() << "\n\n";
    printUsage<Plant>(std::cerr);
    return kExitUsage;
  } catch (const CsvError& e) {
    std::cerr << Plant::program << ": error: " << e.what() << "\n";
    return kExitBadData;
  } catch (const std::exception& e) {
    std::cerr << Plant::program << ": error: " << e.what() << "\n";
    return kExitFailure;
  }
}

}  // namespace mjukf::examples
