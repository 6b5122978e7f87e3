// mjukf_cascaded_tanks: a real plant identified from its recorded data, the Cascaded Tanks benchmark
// (tests/data/cascaded_tanks/README.md), with JUKF, MJUKF (automatic) and the dual UKF under one rule
// for their settings; the benchmark's test, the terms of the model, the rule's sensitivity and the rule
// on the records swapped.
// docs/real-data.md, "Cascaded tanks". Run without arguments for the usage.

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "cascaded/identification.hpp"
#include "cascaded/output_error.hpp"
#include "common/atomic_file.hpp"
#include "common/cli.hpp"
#include "common/csv.hpp"
#include "common/csv_writer.hpp"
#include "common/interrupt.hpp"
#include "common/plot.hpp"

namespace {

using namespace mjukf::examples;
using namespace mjukf::cascaded;

constexpr const char* kProgram = "mjukf_cascaded_tanks";

void printUsage(std::ostream& out) {
  out << "usage: mjukf_cascaded_tanks SUBCOMMAND --data FILE [--out-dir DIR]\n"
      << "\n"
      << "The Cascaded Tanks benchmark (FILE: tests/data/cascaded_tanks/dataBenchmark.csv): identified on\n"
      << "its estimation set, scored by a free run on its test set (docs/real-data.md).\n"
      << "\n"
      << "  identify --data FILE --out-dir DIR\n"
      << "      JUKF, MJUKF (automatic) and the dual UKF, one rule for their settings; writes\n"
      << "      DIR/test_simulation.csv (t,u,y_measured,y_simulated: the JUKF's free run on the test set),\n"
      << "      DIR/results.txt (the test RMS of each beside the published ones) and DIR/test_simulation.png.\n"
      << "  terms --data FILE [--out-dir DIR]\n"
      << "      The output-error fit of each model structure on the estimation set: what each term adds\n"
      << "      (DIR/terms.txt).\n"
      << "  sensitivity --data FILE [--out-dir DIR]\n"
      << "      The JUKF's test RMS with each setting of the rule halved and doubled (DIR/sensitivity.txt).\n"
      << "  crosscheck --data FILE [--out-dir DIR]\n"
      << "      The rule with the two records' roles swapped: identified on the test record, scored on the\n"
      << "      estimation record, which nobody looked at while the rule was made (DIR/crosscheck.txt).\n"
      << "\n"
      << "Output files are written under temporary names and put in place only when the whole run has\n"
      << "succeeded. exit codes: 0 ok; 1 the run failed (a file could not be written, gnuplot failed);\n"
      << "2 malformed or missing data file; 64 bad command line; 128 + N stopped by signal N.\n";
}

std::string fixed(double value, int digits = 3) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  return buffer;
}

std::string describe(const Model& model, const Param& theta) {
  const Model::Physical p = model.physical(theta);
  return "k1 " + fixed(p.k1, 4) + ", k3 " + fixed(p.k3, 4) + ", k4 " + fixed(p.k4, 4) + ", h_max " + fixed(p.hMax, 2) +
         ", k5 " + fixed(p.k5, 3) + ", alpha " + fixed(p.alpha, 3) + ", c " + fixed(p.offset, 3);
}

std::string directory(const Arguments& args) {
  const std::string dir = args.text("--out-dir", ".");
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) throw OutputError(dir + ": cannot create the directory: " + error.message());
  return dir;
}

// The report's text on stdout, and in DIR/name, put in place with the run's other files.
void writeReport(OutputFiles& outputs, const std::string& dir, const std::string& name, const std::string& text) {
  std::cout << text;
  writeText(outputs.add((std::filesystem::path(dir) / name).string()), text);
}

// Each filter identified under the rule, and the output-error fit, scored on the test record: the
// table's rows (model, test RMS, estimation RMS, best pass, refused steps, parameters).
struct Row {
  const char* name;
  Identified identified;
  TestResult test;
};
struct Identifications {
  Rule rule;
  std::vector<Row> rows;
  OutputErrorFit reference;
  TestResult referenceTest;
};

Identifications identifyAll(const Model& model, const Benchmark& b) {
  Identifications all;
  all.rule = makeRule(b);
  all.rows = {{"JUKF", identifyJoint(model, b, all.rule), {}},
              {"MJUKF (automatic)", identifyModified(model, b, all.rule), {}},
              {"dual UKF", identifyDual(model, b, all.rule), {}}};
  for (Row& row : all.rows) row.test = testSimulation(model, row.identified.theta, b);
  all.reference = fitOutputError(model, b, structures().back().free);
  all.referenceTest = testSimulation(model, all.reference.theta, b);
  return all;
}

std::string ruleText(const Rule& rule) {
  return "The rule: R = " + fixed(rule.measurementNoise, 4) +
         " V^2 (100 sigma^2, sigma^2 = " + fixed(rule.sensorVariance, 6) +
         " from the data), Q = " + fixed(rule.levelNoise, 6) + " V^2 per sample, " + std::to_string(rule.passes) +
         " passes (docs/real-data.md).\n\n";
}

std::string resultsTable(const Model& model, const Identifications& all) {
  std::string text =
      "| model | test RMS | estimation RMS | best pass | refused steps | parameters |\n|---|---|---|---|---|---|\n";
  for (const Row& row : all.rows)
    text += std::string("| ") + row.name + " | " + fixed(row.test.rms) + " | " + fixed(row.identified.estimationRms) +
            " | " + std::to_string(row.identified.bestPass + 1) + " | " + std::to_string(row.identified.refused) +
            " | " + describe(model, row.identified.theta) + " |\n";
  text += "| output-error fit of the same model (no filter) | " + fixed(all.referenceTest.rms) + " | " +
          fixed(all.reference.estimationRms) + " | | | " + describe(model, all.reference.theta) + " |\n";
  return text;
}

// Whether the passes settle: each pass's free-run RMS on the record identified on.
std::string passesText(const Identifications& all) {
  std::string text = "Estimation RMS after each pass:\n\n";
  for (const Row& row : all.rows) {
    text += std::string("- ") + row.name + ":";
    for (double error : row.identified.passErrors) text += " " + fixed(error);
    text += "\n";
  }
  return text;
}

int identifyCommand(const Arguments& args) {
  args.requiredText("--out-dir");
  const Benchmark b = loadBenchmark(args.requiredText("--data"));
  const std::string dir = directory(args);
  const Model model;
  const Identifications all = identifyAll(model, b);
  const std::vector<Row>& rows = all.rows;

  std::string text = "# Cascaded Tanks: test RMS error (V)\n\n";
  text +=
      "Identified on the estimation set; on the test set a free run from uVal, its initial state from "
      "yVal[0..4]; RMS over yVal[5..]. " +
      ruleText(all.rule);
  text += resultsTable(model, all);
  text +=
      "| published: best linear approximation | 0.757 | | | | |\n"
      "| published: Volterra | 0.54 | | | | |\n"
      "| published: PNLSS | 0.45 | | | | |\n"
      "| published: NLSS2 | 0.343 | | | | |\n\n";
  text += passesText(all) + "\n";
  // Where the JUKF stopped, against the optimum: a local output-error fit started from its θ̂.
  const OutputErrorFit refined = fitOutputError(model, b, structures().back().free, 1, &rows[0].identified.theta);
  text += "A local output-error fit started from the JUKF's parameters: estimation RMS " +
          fixed(refined.estimationRms) + ", test RMS " + fixed(testSimulation(model, refined.theta, b).rms) + ".\n\n";
  text += "JUKF test RMS: " + fixed(rows[0].test.rms, 4) + " V\n";

  Plotter plotter;
  OutputFiles outputs;
  const std::string csv = (std::filesystem::path(dir) / "test_simulation.csv").string();
  {
    CsvWriter writer(outputs.add(csv), {"t", "u", "y_measured", "y_simulated"});
    for (std::size_t k = 0; k < b.yVal.size(); ++k) {
      writer << double(k) * b.samplePeriod << b.uVal[k] << b.yVal[k] << rows[0].test.simulated[k];
      writer.endRow();
    }
    writer.close();
  }
  writeReport(outputs, dir, "results.txt", text);
  Figure figure;
  figure.png = (std::filesystem::path(dir) / "test_simulation.png").string();
  figure.title = "Cascaded tanks, test set: JUKF model, free run (RMS " + fixed(rows[0].test.rms) + " V)";
  figure.rows = 2;
  figure.panels = {{"lower tank level",
                    "t (s)",
                    "y (V)",
                    {{csv, 1, 3, "measured", "lines lw 1 lc rgb '#1f77b4'"},
                     {csv, 1, 4, "simulated", "lines lw 2 lc rgb '#d62728'"}}},
                   {"pump input", "t (s)", "u (V)", {{csv, 1, 2, "u", "lines lw 1 lc rgb '#2ca02c'"}}}};
  plotter.draw(outputs, figure);
  outputs.commit();
  return kExitOk;
}

int termsCommand(const Arguments& args) {
  const Benchmark b = loadBenchmark(args.requiredText("--data"));
  const std::string dir = directory(args);
  std::string text =
      "# Cascaded Tanks: what each term of the model adds\n\n"
      "Output-error fits on the estimation set (Levenberg-Marquardt, no filter); the test RMS as the "
      "benchmark scores it.\n\n| structure | parameters | estimation RMS (V) | test RMS (V) |\n|---|---|---|---|\n";
  for (const Structure& structure : structures()) {
    Model model;
    model.terms = structure.terms;
    const OutputErrorFit fit = fitOutputError(model, b, structure.free);
    text += "| " + structure.name + " | " + std::to_string(structure.free.size()) + " | " + fixed(fit.estimationRms) +
            " | " + fixed(testSimulation(model, fit.theta, b).rms) + " |\n";
  }
  OutputFiles outputs;
  writeReport(outputs, dir, "terms.txt", text);
  outputs.commit();
  return kExitOk;
}

// The rule on a record it was not made on: the estimation and test records swapped, so the filters
// identify the plant on the benchmark's test record and are scored on its estimation record.
int crosscheckCommand(const Arguments& args) {
  Benchmark b = loadBenchmark(args.requiredText("--data"));
  std::swap(b.uEst, b.uVal);
  std::swap(b.yEst, b.yVal);
  const std::string dir = directory(args);
  const Model model;
  const Identifications all = identifyAll(model, b);
  std::string text =
      "# Cascaded Tanks, the records swapped: identified on the test record, scored on the estimation record (V)\n\n"
      "The rule made afresh from the test record's noise; on the estimation record a free run from uEst, its "
      "initial state from yEst[0..4]; RMS over yEst[5..] (the columns headed test and estimation below are "
      "the records' swapped roles: test = the benchmark's estimation record). " +
      ruleText(all.rule) + resultsTable(model, all) + "\n" + passesText(all) +
      "\nJUKF crosscheck RMS: " + fixed(all.rows[0].test.rms, 4) + " V\n";
  OutputFiles outputs;
  writeReport(outputs, dir, "crosscheck.txt", text);
  outputs.commit();
  return kExitOk;
}

int sensitivityCommand(const Arguments& args) {
  const Benchmark b = loadBenchmark(args.requiredText("--data"));
  const std::string dir = directory(args);
  const Model model;
  const Rule rule = makeRule(b);
  // The test RMS and, beside it, the estimation RMS: what the rule's user could see without the test.
  const auto score = [&](const RuleFactors& f) {
    const Identified identified = identifyJoint(model, b, rule, f);
    return std::pair{testSimulation(model, identified.theta, b).rms, identified.estimationRms};
  };
  const auto [base, baseEstimation] = score({});
  struct Setting {
    const char* name;
    double RuleFactors::*factor;
  };
  const Setting settings[] = {
      {"R (measurement noise)", &RuleFactors::measurementNoise}, {"Q (level noise)", &RuleFactors::levelNoise},
      {"P0 of the parameters", &RuleFactors::parameterSpread},   {"P0 of x1(0)", &RuleFactors::upperLevelSpread},
      {"bounds' width (log units)", &RuleFactors::boundWidth},   {"passes", &RuleFactors::passes}};
  std::string text =
      "# Cascaded Tanks: the rule's sensitivity\n\nThe JUKF's test RMS (V) with one setting of the rule "
      "halved or doubled (in brackets its estimation RMS); the rule itself: " +
      fixed(base) + " (" + fixed(baseEstimation) +
      "). Target: the test RMS within 0.05 of the rule's.\n\n"
      "| setting | halved | doubled | largest change | within 0.05 |\n|---|---|---|---|---|\n";
  for (const Setting& setting : settings) {
    std::string cells;
    double change = 0;
    for (double factor : {0.5, 2.0}) {
      RuleFactors f;
      f.*setting.factor = factor;
      const auto [test, estimation] = score(f);
      cells += fixed(test) + " (" + fixed(estimation) + ") | ";
      change = std::max(change, std::abs(test - base));
    }
    text += std::string("| ") + setting.name + " | " + cells + fixed(change) + " | " +
            (change <= 0.05 ? "yes" : "**no**") + " |\n";
  }
  OutputFiles outputs;
  writeReport(outputs, dir, "sensitivity.txt", text);
  outputs.commit();
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> words(argv + 1, argv + argc);
  if (words.empty() || words[0] == "--help" || words[0] == "-h" || words[0] == "help") {
    printUsage(words.empty() ? std::cerr : std::cout);
    return words.empty() ? kExitUsage : kExitOk;
  }
  handleInterrupts(kProgram);
  try {
    const std::vector<std::string> flags(words.begin() + 1, words.end());
    if (words[0] == "identify") return identifyCommand(Arguments(flags, {"--data", "--out-dir"}));
    if (words[0] == "terms") return termsCommand(Arguments(flags, {"--data", "--out-dir"}));
    if (words[0] == "sensitivity") return sensitivityCommand(Arguments(flags, {"--data", "--out-dir"}));
    if (words[0] == "crosscheck") return crosscheckCommand(Arguments(flags, {"--data", "--out-dir"}));
    throw UsageError("unknown subcommand '" + words[0] + "'");
  } catch (const UsageError& e) {
    std::cerr << kProgram << ": " << e.what() << "\n\n";
    printUsage(std::cerr);
    return kExitUsage;
  } catch (const CsvError& e) {
    std::cerr << kProgram << ": error: " << e.what() << "\n";
    return kExitBadData;
  } catch (const std::exception& e) {
    std::cerr << kProgram << ": error: " << e.what() << "\n";
    return kExitFailure;
  }
}
