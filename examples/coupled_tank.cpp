// mjukf_coupled_tank: simulate the coupled tank, estimate k_flow, reproduce the paper's Table 3.
// Run without arguments for the usage.

#include <array>
#include <optional>

#include "common/plant.hpp"
#include "common/program.hpp"
#include "paper/experiments.hpp"

namespace {

using mjukf::examples::PaperNumbers;
using mjukf::examples::ParameterChange;
using mjukf::examples::Quantity;

struct CoupledTankPlant {
  using Experiment = mjukf::paper::CoupledTankExperiment<double>;
  using Param = Experiment::Param;
  static constexpr const char* program = "mjukf_coupled_tank";
  static constexpr const char* title = "Coupled tank";
  static constexpr const char* slug = "coupled_tank";
  static constexpr const char* simulation = "as the paper: I-TR-BDF2, h = 1 ms, white noise at 30 dB SNR";
  static constexpr const char* table = "Table 3";
  static constexpr std::array<Quantity, 2> states{{{"h1", "upper level h_1", "cm"}, {"h2", "lower level h_2", "cm"}}};
  static constexpr std::array<Quantity, 1> parameters{{{"k_flow", "k_{flow}", "(cm^3/s)/V"}}};
  // Paper Table 3 (Python on an HP Z420, mean of 20 runs).
  static constexpr PaperNumbers<1> published{{0.2919}, {0.2434}, 77.696, 71.191};
  // Conformance RMSEs on the reference file; the reference scripts' times on a 2-core machine.
  static constexpr PaperNumbers<1> reference{{0.2919404233}, {0.2434184329}, 24.7, 25.5};
  static std::optional<ParameterChange<Param>> parameterChange() { return std::nullopt; }
};

}  // namespace

int main(int argc, char** argv) { return mjukf::examples::runProgram<CoupledTankPlant>(argc, argv); }
