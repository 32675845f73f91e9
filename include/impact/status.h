// Status: how every fallible public call reports its outcome. impact never throws
// across its API; a call either succeeds or leaves the world unchanged and says why.
#pragma once

#include <string>
#include <utility>

namespace impact {

/// What went wrong, as a code a program can branch on.
enum class StatusCode : int {
  /// Success.
  kOk = 0,
  kInvalidArgument,   ///< a value is out of its domain (NaN, negative radius, zero normal, ...)
  kSizeMismatch,      ///< two spans that must have equal length do not
  kStaleHandle,       ///< a handle is null, out of range, or refers to a destroyed body
  kCapacityExceeded,  ///< a fixed capacity would be exceeded; the message names it
  kUnsupported,       ///< the requested backend or feature is not built into this library
};

/// The outcome of a call: a code plus a human-readable message that names the
/// offending element and field (for example "body 17: radius must be > 0, got -1").
class [[nodiscard]] Status {
 public:
  /// Success (kOk, empty message).
  Status() = default;
  /// An outcome with its code and message.
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}

  /// True when the call succeeded.
  bool ok() const { return code_ == StatusCode::kOk; }
  /// The code, for branching on the kind of failure.
  StatusCode code() const { return code_; }
  /// Empty on success.
  const std::string& message() const { return message_; }

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

/// Name of a status code, for messages and logs.
const char* to_string(StatusCode code);

}  // namespace impact
