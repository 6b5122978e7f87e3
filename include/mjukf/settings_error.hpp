#pragma once

/// \file
/// What an invalid setting is reported as: a small value naming it, without a string or the heap, so
/// that firmware built without exceptions gets the same diagnosis as a host build (docs/embedded.md).

/// MJUKF_EXCEPTIONS is 1 when the library reports an invalid setting by throwing std::invalid_argument
/// (the default wherever exceptions are on) and 0 when it only returns a `SettingsError`: with
/// exceptions off (-fno-exceptions), or when MJUKF_NO_EXCEPTIONS is defined.
#if defined(MJUKF_NO_EXCEPTIONS) || !(defined(__cpp_exceptions) || defined(__EXCEPTIONS) || defined(_CPPUNWIND))
#define MJUKF_EXCEPTIONS 0
#else
#define MJUKF_EXCEPTIONS 1
#endif

namespace mjukf {

/// An invalid setting, or none: `owner` is the class that checked it ("mjukf::Ukf"), `setting` the
/// setting or argument ("measurementNoise (R)"), `reason` what is wrong with it ("must be symmetric").
/// All three are string literals. Converts to true when there is an error, like std::error_code; a
/// default-constructed value is "no error". With exceptions on, the message of the std::invalid_argument
/// the library throws is "<owner>: setting '<setting>' <reason>".
struct [[nodiscard]] SettingsError {
  /// The class that checked the setting, e.g. "mjukf::Ukf"; null when there is no error.
  const char* owner = nullptr;
  /// The setting or argument, e.g. "measurementNoise (R)"; null when there is no error.
  const char* setting = nullptr;
  /// What is wrong with it, e.g. "must be symmetric"; null when there is no error.
  const char* reason = nullptr;

  /// True when there is an error (a setting is named).
  constexpr explicit operator bool() const noexcept { return setting != nullptr; }
};

/// What `reset()` of a filter returns: nothing with exceptions on (it throws std::invalid_argument
/// naming the argument), the `SettingsError` without them. Either way an invalid argument changes nothing.
#if MJUKF_EXCEPTIONS
using ResetResult = void;
#else
using ResetResult = SettingsError;
#endif

}  // namespace mjukf
