#pragma once

/// \file
/// `Result<T>`: a filter or stepper built by its `create(...)` factory, or the `SettingsError` that
/// stopped it, the way to construct one without exceptions (docs/embedded.md).

#include <new>
#include <type_traits>
#include <utility>

#include "mjukf/settings_error.hpp"

#if MJUKF_EXCEPTIONS
#include "mjukf/detail/validation.hpp"
#endif

namespace mjukf {

/// \cond INTERNAL
namespace detail {
struct BuildWith {};  // tag of Result's constructor from a callable returning T
}  // namespace detail
/// \endcond

/// Holds a T, built in place, or the SettingsError that stopped its construction; never both, never a
/// half-built T. `create()` returns it by value with guaranteed copy elision (C++17): the T is built
/// once, in the Result, and never copied on the way out, however large it is. The T is a member of
/// an anonymous union, so the Result has the alignment of T (fixed-size Eigen members need 16 bytes on
/// some targets) on the stack, as a member and, with C++17's aligned new, on the heap.
template <class T>
class Result {
 public:
  /// A failed construction.
  Result(SettingsError error) : error_(error) {}  // NOLINT: implicit, for `return error;`
  /// Builds the T from `make()`, a callable returning a T prvalue: no copy, no move (C++17).
  template <class Make>
  Result(detail::BuildWith, Make&& make) {
    ::new (static_cast<void*>(&value_)) T(make());
  }
  /// Copies the T, or the error.
  Result(const Result& other) : error_(other.error_) {
    if (!error_) ::new (static_cast<void*>(&value_)) T(other.value_);
  }
  /// Moves the T out of `other` (left holding a moved-from T), or copies the error.
  Result(Result&& other) noexcept(std::is_nothrow_move_constructible_v<T>) : error_(other.error_) {
    if (!error_) ::new (static_cast<void*>(&value_)) T(std::move(other.value_));
  }
  Result& operator=(const Result&) = delete;
  Result& operator=(Result&&) = delete;
  ~Result() {
    if (!error_) value_.~T();
  }

  /// True when the T was built.
  bool ok() const noexcept { return !error_; }
  /// ok(): true when the T was built.
  explicit operator bool() const noexcept { return ok(); }
  /// The error; "no error" (false) when ok().
  const SettingsError& error() const noexcept { return error_; }

  /// The T. Without one (!ok()): throws std::invalid_argument with the error's message when
  /// exceptions are on, otherwise traps (__builtin_trap): a filter that failed validation is never
  /// usable.
  T& value() & { return ok() ? value_ : fail(); }
  /// The T, read-only; as value().
  const T& value() const& { return ok() ? value_ : fail(); }
  /// value().
  T& operator*() & { return value(); }
  /// value(), read-only.
  const T& operator*() const& { return value(); }
  /// &value().
  T* operator->() { return &value(); }
  /// &value(), read-only.
  const T* operator->() const { return &value(); }

 private:
  [[noreturn]] T& fail() const {
#if MJUKF_EXCEPTIONS
    detail::throwInvalid(error_);
#else
    __builtin_trap();
#endif
  }

  SettingsError error_;
  union {
    T value_;
  };
};

/// \cond INTERNAL
namespace detail {

// What a create() returns: `error`, or the T that `make()` returns, built in place. `make` is a lambda
// of the class, so it may call its private constructor.
template <class T, class Make>
Result<T> resultOf(const SettingsError& error, Make&& make) {
  if (error) return error;
  return {BuildWith{}, std::forward<Make>(make)};
}

}  // namespace detail
/// \endcond
}  // namespace mjukf
