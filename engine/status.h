// Status and Expected<T>: systems report errors as values; exceptions are
// reserved for I/O and API entry points (PMP style).
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

namespace atelier {

enum class ErrorCode {
  kOk = 0,
  kInvalidArgument,   // bad parameter value
  kStaleHandle,       // handle refers to a dead or reused slot
  kTopology,          // operation would break a topological invariant
  kNonManifold,       // non-manifold configuration where a manifold one is required
  kJointRefused,      // operation not allowed on a joint edge
  kDegenerate,        // degenerate geometry (zero area, NaN)
  kParse,             // malformed input file
  kIo,                // file system error
  kMismatch,          // mismatched topologies or sizes
  kCancelled,         // cancelled through the ExecContext
  kUnsupported,
  kInternal,
};

[[nodiscard]] const char* to_string(ErrorCode c) noexcept;

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(ErrorCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status ok() { return {}; }

  [[nodiscard]] bool is_ok() const noexcept { return code_ == ErrorCode::kOk; }
  explicit operator bool() const noexcept { return is_ok(); }
  [[nodiscard]] ErrorCode code() const noexcept { return code_; }
  [[nodiscard]] const std::string& message() const noexcept { return message_; }
  [[nodiscard]] std::string to_string() const;

 private:
  ErrorCode code_ = ErrorCode::kOk;
  std::string message_;
};

/// Thrown only at I/O and API entry points.
class Error : public std::runtime_error {
 public:
  explicit Error(Status s) : std::runtime_error(s.to_string()), status_(std::move(s)) {}
  [[nodiscard]] const Status& status() const noexcept { return status_; }

 private:
  Status status_;
};

template <class T>
class [[nodiscard]] Expected {
 public:
  Expected(T value) : v_(std::move(value)) {}  // NOLINT(google-explicit-constructor)
  Expected(Status s) : v_(std::move(s)) {}     // NOLINT(google-explicit-constructor)

  [[nodiscard]] bool has_value() const noexcept { return v_.index() == 0; }
  explicit operator bool() const noexcept { return has_value(); }
  [[nodiscard]] T& value() & {
    if (!has_value()) throw Error(std::get<1>(v_));
    return std::get<0>(v_);
  }
  [[nodiscard]] const T& value() const& {
    if (!has_value()) throw Error(std::get<1>(v_));
    return std::get<0>(v_);
  }
  [[nodiscard]] T&& value() && {
    if (!has_value()) throw Error(std::get<1>(v_));
    return std::get<0>(std::move(v_));
  }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  [[nodiscard]] Status status() const { return has_value() ? Status{} : std::get<1>(v_); }

 private:
  std::variant<T, Status> v_;
};

}  // namespace atelier
