// mjukf_lorenz: the Lorenz system of the 2019 MJUKF paper; simulate it, estimate (σ, ρ, β), study the
// filters over many noise draws. Run without arguments for the usage.

#include <array>
#include <optional>

#include "common/plant.hpp"
#include "common/program.hpp"
#include "paper/systems_2019.hpp"

namespace {

using mjukf::examples::ParameterChange;
using mjukf::examples::Quantity;

struct LorenzPlant {
  using Experiment = mjukf::paper::LorenzExperiment<double>;
  using Param = Experiment::Param;
  static constexpr const char* program = "mjukf_lorenz";
  static constexpr const char* title = "Lorenz system (2019 MJUKF paper)";
  static constexpr const char* slug = "lorenz";
  static constexpr const char* simulation = "as the 2019 paper: RK4, h = 0.01 s, 100 s, noise std 0.1 |x_i|";
  static constexpr std::array<Quantity, 3> parameters{{{"sigma", "σ", "-"}, {"rho", "ρ", "-"}, {"beta", "β", "-"}}};
  static std::optional<ParameterChange<Param>> parameterChange() { return std::nullopt; }
};

}  // namespace

int main(int argc, char** argv) { return mjukf::examples::runProgram<LorenzPlant>(argc, argv); }
