// mjukf_gallery: five plants of the library's own design that its filters were not made for (a DC motor
// measured by its angle, a battery in discrete time, predator and prey, a heated block with fast and
// slow dynamics, a drug with saturable elimination); simulate them, estimate their parameters, study the
// filters over many noise draws. `mjukf_gallery PLANT SUBCOMMAND [flags]`; run without arguments for
// the plants. docs/studies.md, "The gallery".

#include <array>
#include <cstring>
#include <iostream>
#include <optional>
#include <string>

#include "common/cli.hpp"
#include "common/plant.hpp"
#include "common/program.hpp"
#include "gallery/experiments.hpp"

namespace {

using mjukf::examples::ParameterChange;
using mjukf::examples::Quantity;

// What every gallery plant's description (common/plant.hpp) shares: its experiment, no parameter change.
template <class Experiment_>
struct GalleryPlant {
  using Experiment = Experiment_;
  using Param = typename Experiment::Param;
  static std::optional<ParameterChange<Param>> parameterChange() { return std::nullopt; }
};

struct DcMotorPlant : GalleryPlant<mjukf::gallery::DcMotorExperiment<double>> {
  static constexpr const char* program = "mjukf_gallery dc_motor";
  static constexpr const char* title = "DC motor measured by its angle (gallery)";
  static constexpr const char* slug = "dc_motor";
  static constexpr const char* character = "one measured output, parameters of opposite-sign sensitivity";
  static constexpr const char* simulation = "I-TR-BDF2, h = 1 ms, 20 s from rest, angle noise std 5 mrad";
  static constexpr std::array<Quantity, 2> parameters{{{"K", "K", "N m/A"}, {"b", "b", "N m s/rad"}}};
};

struct BatteryPlant : GalleryPlant<mjukf::gallery::BatteryExperiment<double>> {
  static constexpr const char* program = "mjukf_gallery battery";
  static constexpr const char* title = "Battery, discrete-time Thevenin circuit (gallery)";
  static constexpr const char* slug = "battery";
  static constexpr const char* character = "discrete time, a measurement that depends on the input";
  static constexpr const char* simulation = "discrete time, 1 s samples, 1 h from 90% charge, voltage noise std 2 mV";
  static constexpr std::array<Quantity, 2> parameters{{{"R0", "R_0", "Ohm"}, {"R1", "R_1", "Ohm"}}};
};

struct PredatorPreyPlant : GalleryPlant<mjukf::gallery::PredatorPreyExperiment<double>> {
  static constexpr const char* program = "mjukf_gallery predator_prey";
  static constexpr const char* title = "Predator and prey, prey measured (gallery)";
  static constexpr const char* slug = "predator_prey";
  static constexpr const char* character = "an unmeasured state guessed 2.5x wrong, its parameters";
  static constexpr const char* timeUnit = "year";
  static constexpr const char* simulation = "RK4, h = 0.1 year, 100 years, prey count noise std 0.3 thousand";
  static constexpr std::array<Quantity, 2> parameters{{{"delta", "δ", "1/(year thousand)"}, {"gamma", "γ", "1/year"}}};
};

struct HeatedBlockPlant : GalleryPlant<mjukf::gallery::HeatedBlockExperiment<double>> {
  static constexpr const char* program = "mjukf_gallery heated_block";
  static constexpr const char* title = "Heated block, fast and slow (gallery)";
  static constexpr const char* slug = "heated_block";
  static constexpr const char* character = "fast (0.1 s) and slow (200 s) dynamics";
  static constexpr const char* simulation = "I-TR-BDF2, h = 20 ms, 1800 s, temperature noise std 0.1 K";
  static constexpr std::array<Quantity, 2> parameters{{{"G_hb", "G_{hb}", "W/K"}, {"G_ba", "G_{ba}", "W/K"}}};
};

struct DrugInfusionPlant : GalleryPlant<mjukf::gallery::DrugInfusionExperiment<double>> {
  static constexpr const char* program = "mjukf_gallery drug_infusion";
  static constexpr const char* title = "Drug infusion, Michaelis-Menten elimination (gallery)";
  static constexpr const char* slug = "drug_infusion";
  static constexpr const char* character = "a parameter that enters nonlinearly (K_m)";
  static constexpr const char* timeUnit = "h";
  static constexpr const char* simulation = "I-TR-BDF2, h = 0.01 h, 72 h, concentration noise std 0.2 mg/L";
  static constexpr std::array<Quantity, 2> parameters{{{"V_max", "V_{max}", "mg/(L h)"}, {"K_m", "K_m", "mg/L"}}};
};

template <class... Plants>
struct Gallery {
  static void printUsage(std::ostream& out) {
    out << "usage: mjukf_gallery PLANT SUBCOMMAND [--flag value ...]\n"
        << "\n"
        << "Five plants the filters were not made for, each with one rule for every filter's settings\n"
        << "(docs/studies.md, \"The gallery\"). PLANT is one of:\n"
        << "\n";
    ((out << "  " << Plants::slug << std::string(15 - std::strlen(Plants::slug), ' ') << Plants::title << "\n"
          << std::string(17, ' ') << Plants::character << "\n"),
     ...);
    out << "\n"
        << "SUBCOMMAND is simulate, estimate or study, as for the other example programs;\n"
        << "`mjukf_gallery PLANT --help` gives a plant's usage.\n";
  }

  // Runs the plant named argv[1] with the rest of the command line; -1 when no plant has that name.
  static int run(int argc, char** argv) {
    int code = -1;
    static_cast<void>(((std::strcmp(argv[1], Plants::slug) == 0 &&
                        (code = mjukf::examples::runProgram<Plants>(argc - 1, argv + 1), true)) ||
                       ...));
    return code;
  }
};

using AllPlants = Gallery<DcMotorPlant, BatteryPlant, PredatorPreyPlant, HeatedBlockPlant, DrugInfusionPlant>;

}  // namespace

int main(int argc, char** argv) {
  using namespace mjukf::examples;
  const std::string first = argc > 1 ? argv[1] : "";
  if (first.empty() || first == "--help" || first == "-h" || first == "help") {
    AllPlants::printUsage(first.empty() ? std::cerr : std::cout);
    return first.empty() ? kExitUsage : kExitOk;
  }
  const int code = AllPlants::run(argc, argv);
  if (code >= 0) return code;
  std::cerr << "mjukf_gallery: unknown plant '" << first << "'\n\n";
  AllPlants::printUsage(std::cerr);
  return kExitUsage;
}
