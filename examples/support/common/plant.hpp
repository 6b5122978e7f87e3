#pragma once

// What the example programs need to know about a plant beyond its model: names and units for the
// CSV summaries and the plots, the paper's published numbers, and the optional parameter-change
// scenario. Each program defines one such description; everything else is shared.
//
// A plant description `Plant` provides:
//
//   using Experiment = mjukf::paper::…Experiment<double>;   // model, settings, schedule of the paper
//   static constexpr const char* program;                   // executable name, for messages
//   static constexpr const char* title;                     // "Coupled tank"
//   static constexpr const char* slug;                      // "coupled_tank", for file names
//   static constexpr const char* simulation;                // how `simulate` makes data, for the usage
//   static constexpr std::array<Quantity, ParamDim> parameters;
//   static std::optional<ParameterChange<Param>> parameterChange();
//
// optionally the unit of the model's time, for the messages (seconds unless it says otherwise):
//
//   static constexpr const char* timeUnit;                  // "year"
//
// and, for the paper's plants only (the `paper` subcommand exists where they are given):
//
//   static constexpr std::array<Quantity, StateDim> states;  // for the state figures
//   static constexpr const char* table;                     // "Table 3"
//   static constexpr PaperNumbers<ParamDim> published;       // paper's table (Python, HP Z420, mean of 20)
//   static constexpr PaperNumbers<ParamDim> reference;       // conformance RMSEs; reference scripts' times

#include <array>
#include <type_traits>

namespace mjukf::examples {

/// A named physical quantity: plain name for the console, gnuplot (enhanced-text) label, unit.
struct Quantity {
  const char* name;
  const char* label;
  const char* unit;
};

/// RMSE per parameter and run time of JUKF and MJUKF as a table reports them.
template <int ParamDim>
struct PaperNumbers {
  std::array<double, ParamDim> jukfRmse;
  std::array<double, ParamDim> mjukfRmse;
  double jukfSeconds;
  double mjukfSeconds;
};

/// The paper's parameter-change scenario: from time `at` the plant runs with `after`; the run lasts
/// `duration`, and MJUKF uses ξ = `scaling`.
template <class Param>
struct ParameterChange {
  double at;
  double duration;
  Param after;
  double scaling;
};

/// Q_θ (times I) of the dual UKF where the parameters change (`paper`'s and `study`'s change runs): JUKF's
/// random walk of the paper's robot, which lets it follow the change. The presets assume constant
/// parameters, Q_θ = 0.
constexpr double kChangeParameterProcessNoise = 1e-5;

namespace detail {
template <class Plant, class = void>
struct HasPaperTable : std::false_type {};
template <class Plant>
struct HasPaperTable<Plant, std::void_t<decltype(Plant::published), decltype(Plant::reference), decltype(Plant::table)>>
    : std::true_type {};
}  // namespace detail

/// True for the paper's plants, which have a published table to compare with (`paper` subcommand).
template <class Plant>
inline constexpr bool hasPaperTable = detail::HasPaperTable<Plant>::value;

namespace detail {
template <class Plant, class = void>
struct TimeUnit {
  static constexpr const char* value = "s";
};
template <class Plant>
struct TimeUnit<Plant, std::void_t<decltype(Plant::timeUnit)>> {
  static constexpr const char* value = Plant::timeUnit;
};
}  // namespace detail

/// The unit of the plant's model time in messages: `Plant::timeUnit`, or "s".
template <class Plant>
inline constexpr const char* timeUnit = detail::TimeUnit<Plant>::value;

}  // namespace mjukf::examples
