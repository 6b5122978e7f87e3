// mjukf_flexible_joint: simulate the flexible-joint robot, estimate (K_τ, m), reproduce the paper's
// Table 4 and the parameter-change scenario of Figs. 12–14. Run without arguments for the usage.

#include <array>
#include <optional>

#include "common/plant.hpp"
#include "common/program.hpp"
#include "paper/experiments.hpp"

namespace {

using mjukf::examples::PaperNumbers;
using mjukf::examples::ParameterChange;
using mjukf::examples::Quantity;

struct FlexibleJointPlant {
  using Experiment = mjukf::paper::FlexibleJointExperiment<double>;
  using Param = Experiment::Param;
  static constexpr const char* program = "mjukf_flexible_joint";
  static constexpr const char* title = "Flexible-joint robot";
  static constexpr const char* slug = "flexible_joint";
  static constexpr const char* simulation = "as the paper: I-TR-BDF2, h = 1 ms, white noise at 30 dB SNR";
  static constexpr const char* table = "Table 4";
  static constexpr std::array<Quantity, 4> states{{{"theta_m", "motor angle θ_m", "rad"},
                                                   {"omega_m", "motor speed ω_m", "rad/s"},
                                                   {"theta_l", "link angle θ_l", "rad"},
                                                   {"omega_l", "link speed ω_l", "rad/s"}}};
  static constexpr std::array<Quantity, 2> parameters{{{"K_tau", "K_τ", "N m/V"}, {"m", "m", "kg"}}};
  // Paper Table 4 (Python on an HP Z420, mean of 20 runs).
  static constexpr PaperNumbers<2> published{{0.0177, 0.019}, {0.008, 0.01233}, 4.337, 3.717};
  // Conformance RMSEs on the reference file; the reference scripts' times on a 2-core machine.
  static constexpr PaperNumbers<2> reference{
      {0.02671036066, 0.03426798571}, {0.006717243853, 0.008727060131}, 1.56, 1.06};
  // docs/plants.md §3: at t = 5 s, K_τ becomes 0.10 and m 0.30; 30 s; MJUKF with ξ = −0.0035.
  static std::optional<ParameterChange<Param>> parameterChange() {
    return ParameterChange<Param>{5.0, 30.0, Param(0.10, 0.30), Experiment::parameterChangeScaling};
  }
};

}  // namespace

int main(int argc, char** argv) { return mjukf::examples::runProgram<FlexibleJointPlant>(argc, argv); }
