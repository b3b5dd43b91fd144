// SPDX-License-Identifier: Apache-2.0
// The commands taken from the broker: parsed from their JSON, checked against the bridge's
// permission (fleet.commands, the D-Bus groups' split) and turned into the daemon's D-Bus
// method call, whose own checks (ranges, state) then apply. docs/fleet.md lists them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace weedspray::fleet {

// Why a command was not carried out; each is counted and published.
enum class Refusal { kNone, kMalformed, kUnknown, kUnauthorised, kUnsupported, kFailed };
[[nodiscard]] std::string_view refusal_name(Refusal refusal);

// One D-Bus method call of org.weedspray.Sprayer1: its name and (for SetPressureSetpoint,
// SetDecisionThreshold, SetTargetRate) its one double argument.
struct MethodCall {
  std::string method;
  std::optional<double> argument;
};

struct ParsedCommand {
  std::string kind;             // "start", "set_pressure" ... ("" when malformed)
  nlohmann::json id = nullptr;  // the sender's id, echoed in the reply
  Refusal refusal = Refusal::kNone;
  std::string message;  // why refused
  MethodCall call;      // when not refused
};

// The largest command payload read.
inline constexpr std::size_t kMaxCommandBytes = 4096;

// Parses `payload` and checks the kind against `permission` (none | operator | admin).
[[nodiscard]] ParsedCommand parse_command(std::string_view payload, std::string_view permission);

// The reply published for a command: {"id", "command", "ok", "reason", "message"}.
[[nodiscard]] nlohmann::json command_reply(const ParsedCommand& command, Refusal refusal,
                                           const std::string& message);

// How many commands arrived and how each ended, published retained as .../commands.
struct CommandCounters {
  std::uint64_t received = 0;
  std::uint64_t done = 0;
  std::uint64_t malformed = 0;
  std::uint64_t unknown = 0;
  std::uint64_t unauthorised = 0;
  std::uint64_t unsupported = 0;
  std::uint64_t failed = 0;  // the daemon refused it (its checks) or did not answer

  void count(Refusal refusal);
  [[nodiscard]] nlohmann::json to_json() const;
};

}  // namespace weedspray::fleet
