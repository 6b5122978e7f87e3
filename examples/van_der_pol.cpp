// mjukf_van_der_pol: the Van der Pol oscillator of the 2019 MJUKF paper; simulate it, estimate μ,
// study the filters over many noise draws. Run without arguments for the usage.

#include <array>
#include <optional>

#include "common/plant.hpp"
#include "common/program.hpp"
#include "paper/systems_2019.hpp"

namespace {

using mjukf::examples::ParameterChange;
using mjukf::examples::Quantity;

struct VanDerPolPlant {
  using Experiment = mjukf::paper::VanDerPolExperiment<double>;
  using Param = Experiment::Param;
  static constexpr const char* program = "mjukf_van_der_pol";
  static constexpr const char* title = "Van der Pol oscillator (2019 MJUKF paper)";
  static constexpr const char* slug = "van_der_pol";
  static constexpr const char* simulation = "as the 2019 paper: RK4, h = 0.1 s, 100 s, noise std 0.1 |x_i|";
  static constexpr std::array<Quantity, 1> parameters{{{"mu", "μ", "-"}}};
  static std::optional<ParameterChange<Param>> parameterChange() { return std::nullopt; }
};

}  // namespace

int main(int argc, char** argv) { return mjukf::examples::runProgram<VanDerPolPlant>(argc, argv); }
