// Command-line reading shared by the bench tools' mains (bench/scenes/throughput.cpp,
// bench/rigid_peers.cpp): their exit status for bad arguments, a whole-string unsigned
// parse, and a cursor over argv that reads each option as `--name value` or
// `--name=value` and reports a bad one.
#pragma once

#include <charconv>
#include <cstdio>
#include <string>
#include <string_view>
#include <system_error>

namespace impact::bench {

/// The tools' exit status for bad arguments, and what their parse_args returns for --help.
inline constexpr int kExitUsage = 2;
inline constexpr int kAskedForHelp = -1;

/// Whole-string unsigned parse: rejects signs, blanks, trailing junk and overflow; base
/// 16 also takes a 0x prefix.
template <class T>
bool parse_unsigned(std::string_view s, T* out, int base = 10) {
  if (base == 16 && (s.starts_with("0x") || s.starts_with("0X"))) s.remove_prefix(2);
  if (s.empty()) return false;
  T v{};
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v, base);
  if (ec != std::errc() || ptr != s.data() + s.size()) return false;
  *out = v;
  return true;
}

/// The options of argv[1 .. argc) one at a time: name() is the option (before any '='),
/// value() its value once there is one (after '=', or the next argument taken by
/// need_value()); fail() reports a bad one in the name of the tool.
class ArgCursor {
 public:
  ArgCursor(int argc, char** argv, const char* tool) : argc_(argc), argv_(argv), tool_(tool) {}

  /// Moves to the next option; false past the last.
  bool next() {
    if (++i_ >= argc_) return false;
    name_ = argv_[i_];
    value_ = {};
    has_value_ = false;
    if (const size_t eq = name_.find('='); name_.starts_with("--") && eq != std::string_view::npos) {
      value_ = name_.substr(eq + 1);
      name_ = name_.substr(0, eq);
      has_value_ = true;
    }
    return true;
  }

  /// The option's value: after its '=', else the next argument (taken). False when
  /// there is none.
  bool need_value() {
    if (has_value_) return true;
    if (i_ + 1 >= argc_) return false;
    value_ = argv_[++i_];
    has_value_ = true;
    return true;
  }

  /// Whether the option has a value yet (given with '=', or taken by need_value()).
  bool has_value() const { return has_value_; }
  std::string_view name() const { return name_; }
  const std::string_view& value() const { return value_; }
  /// The option as given (with any '=value').
  const char* raw() const { return argv_[i_]; }

  /// Prints "<tool>: <msg>" and where to find the usage to stderr; returns kExitUsage.
  int fail(const std::string& msg) const {
    std::fprintf(stderr, "%s: %s\n(see %s --help)\n", tool_, msg.c_str(), tool_);
    return kExitUsage;
  }

 private:
  int argc_;
  char** argv_;
  const char* tool_;
  int i_ = 0;
  std::string_view name_, value_;
  bool has_value_ = false;
};

}  // namespace impact::bench
