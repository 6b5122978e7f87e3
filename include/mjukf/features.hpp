#pragma once

/// \file
/// The optional parts of a filter that can be compiled out, its last template argument (after the
/// covariance form): `AllFeatures` (the default) or `Without<…>` the features a firmware does not use.
/// A feature compiled out has no state in the filter object and no code in the image; settings that
/// ask for it are refused by the factory (`create`) and the constructor, naming the setting and the
/// opt-out, and its accessors do not compile. docs/embedded.md says how to choose.

#include <type_traits>

/// \cond INTERNAL
// A member of an empty type (a compiled-out feature's state) takes no room in the object. GCC and Clang
// honour the C++20 attribute in C++17 too; MSVC has its own spelling.
#if defined(_MSC_VER) && !defined(__clang__)
#define MJUKF_NO_UNIQUE_ADDRESS [[msvc::no_unique_address]]
#else
#define MJUKF_NO_UNIQUE_ADDRESS [[no_unique_address]]
#endif
/// \endcond

namespace mjukf {

/// The features `Without` can omit.
namespace feature {
/// The health monitor (health.hpp): `health()`, `healthStatistics()`, `clearHealth()` and the
/// setting `health`. Every filter has it. Compiled out, `health.enabled` must be false.
struct HealthMonitor {};
/// The MJUKF's automatic modes (parameter_sensitivity.hpp, docs/tuning-mjukf.md): the settings
/// `automaticTransformation` and `adaptiveScaling`, the sensitivities they follow and `sensitivity()`,
/// and the covariance of θ̂ that follows the same sensitivities (`followParameterCovariance`;
/// `parameterCovariance()` is then NaN, unknown), with what it adds to the state's covariance
/// (`parameterUncertaintyInState`, which acts only with `adaptiveScaling`). Only `ModifiedJointUkf` has
/// them; the other filters accept the tag and are unchanged by it. Compiled out, the first three
/// settings must be false.
struct AutomaticModes {};
}  // namespace feature

/// The features of a filter: what `Without<…>` and `AllFeatures` name (one type per combination,
/// whatever the order of the tags). Read by the filters; name it through `Without`.
template <bool HealthMonitor, bool AutomaticModes>
struct FeatureSet {
  /// Whether the filter has its health monitor.
  static constexpr bool healthMonitor = HealthMonitor;
  /// Whether the MJUKF has its automatic modes.
  static constexpr bool automaticModes = AutomaticModes;
};

/// \cond INTERNAL
namespace detail {
// Whether `Feature` is among `Omitted`, which must all be tags of mjukf::feature.
template <class Feature, class... Omitted>
constexpr bool omits() {
  static_assert(
      (... && (std::is_same_v<Omitted, feature::HealthMonitor> || std::is_same_v<Omitted, feature::AutomaticModes>)),
      "mjukf::Without<...> takes the tags of mjukf::feature: HealthMonitor, AutomaticModes");
  return (... || std::is_same_v<Omitted, Feature>);
}
template <class Features>
inline constexpr bool isFeatureSet = false;
template <bool HealthMonitor, bool AutomaticModes>
inline constexpr bool isFeatureSet<FeatureSet<HealthMonitor, AutomaticModes>> = true;
// What a compiled-out feature's state is: an empty member (MJUKF_NO_UNIQUE_ADDRESS) built from
// whatever the feature's state would have been built from. Empty members of one type must have
// distinct addresses, so each absent member of a class takes its own `Id`.
template <int Id = 0>
struct Absent {
  Absent() = default;
  template <class... Arguments>
  explicit Absent(const Arguments&...) {}
};
}  // namespace detail
/// \endcond

/// A filter's features with those listed omitted, e.g.
/// `ModifiedJointUkf<Model, DefaultIntegrator<Model>, MerweScaled, FullCovariance,
/// Without<feature::HealthMonitor, feature::AutomaticModes>>`.
template <class... Omitted>
using Without = FeatureSet<!detail::omits<feature::HealthMonitor, Omitted...>(),
                           !detail::omits<feature::AutomaticModes, Omitted...>()>;

/// Every feature compiled in: the default of every filter.
using AllFeatures = Without<>;

}  // namespace mjukf
