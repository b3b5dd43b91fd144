// SPDX-License-Identifier: Apache-2.0
#include "fleet/fleet_commands.hpp"

#include <array>

namespace weedspray::fleet {
namespace {

enum class Level { kOperator, kAdmin };

struct CommandKind {
  std::string_view name;
  const char* method;  // nullptr: the daemon has no D-Bus method for it
  Level level;
  const char* number_field;  // the one number argument, or nullptr
};

// Operator kinds are those group weedspray may call over D-Bus, admin those only
// weedspray-admin may (systemd/org.weedspray.Sprayer1.conf).
constexpr std::array<CommandKind, 7> kKinds = {{
    {"start", "Start", Level::kOperator, nullptr},
    {"stop", "Stop", Level::kOperator, nullptr},
    {"set_pressure", "SetPressureSetpoint", Level::kOperator, "mpa"},
    {"clear_alarms", "ClearAlarms", Level::kOperator, nullptr},
    {"reload_config", "ReloadConfig", Level::kAdmin, nullptr},
    {"threshold", "SetDecisionThreshold", Level::kOperator, "value"},
    {"rate", "SetTargetRate", Level::kOperator, "l_per_ha"},
}};

bool permits(std::string_view permission, Level level) {
  if (permission == "admin") return true;
  if (permission == "operator") return level == Level::kOperator;
  return false;
}

ParsedCommand refused(ParsedCommand command, Refusal refusal, std::string message) {
  command.refusal = refusal;
  command.message = std::move(message);
  return command;
}

}  // namespace

std::string_view refusal_name(Refusal refusal) {
  switch (refusal) {
    case Refusal::kNone:
      return "";
    case Refusal::kMalformed:
      return "malformed";
    case Refusal::kUnknown:
      return "unknown";
    case Refusal::kUnauthorised:
      return "unauthorised";
    case Refusal::kUnsupported:
      return "unsupported";
    case Refusal::kFailed:
      return "failed";
  }
  return "?";
}

ParsedCommand parse_command(std::string_view payload, std::string_view permission) {
  ParsedCommand command;
  if (payload.size() > kMaxCommandBytes) {
    return refused(command, Refusal::kMalformed,
                   "longer than " + std::to_string(kMaxCommandBytes) + " bytes");
  }
  const auto json = nlohmann::json::parse(payload, nullptr, false);
  if (json.is_discarded() || !json.is_object()) {
    return refused(command, Refusal::kMalformed, "not a JSON object");
  }
  if (json.contains("id")) command.id = json["id"];
  const auto kind = json.find("command");
  if (kind == json.end() || !kind->is_string()) {
    return refused(command, Refusal::kMalformed, "no \"command\" string");
  }
  command.kind = kind->get<std::string>();
  const CommandKind* found = nullptr;
  for (const auto& candidate : kKinds) {
    if (candidate.name == command.kind) found = &candidate;
  }
  if (found == nullptr) {
    return refused(command, Refusal::kUnknown, "no command \"" + command.kind + "\"");
  }
  if (!permits(permission, found->level)) {
    std::string message = "this board takes ";
    message += permission == "none" ? "no commands" : std::string(permission) + " commands only";
    message += " from the broker (fleet.commands)";
    return refused(command, Refusal::kUnauthorised, message);
  }
  if (found->number_field != nullptr) {
    const auto value = json.find(found->number_field);
    if (value == json.end() || !value->is_number()) {
      return refused(command, Refusal::kMalformed,
                     "\"" + command.kind + "\" needs the number \"" + found->number_field + "\"");
    }
    command.call.argument = value->get<double>();
  }
  if (found->method == nullptr) {
    return refused(command, Refusal::kUnsupported,
                   "weedsprayd offers no D-Bus method for \"" + command.kind + "\" yet");
  }
  command.call.method = found->method;
  return command;
}

nlohmann::json command_reply(const ParsedCommand& command, Refusal refusal,
                             const std::string& message) {
  return {{"id", command.id},
          {"command", command.kind},
          {"ok", refusal == Refusal::kNone},
          {"reason", refusal_name(refusal)},
          {"message", message}};
}

void CommandCounters::count(Refusal refusal) {
  ++received;
  switch (refusal) {
    case Refusal::kNone:
      ++done;
      break;
    case Refusal::kMalformed:
      ++malformed;
      break;
    case Refusal::kUnknown:
      ++unknown;
      break;
    case Refusal::kUnauthorised:
      ++unauthorised;
      break;
    case Refusal::kUnsupported:
      ++unsupported;
      break;
    case Refusal::kFailed:
      ++failed;
      break;
  }
}

nlohmann::json CommandCounters::to_json() const {
  return {{"received", received},
          {"done", done},
          {"malformed", malformed},
          {"unknown", unknown},
          {"unauthorised", unauthorised},
          {"unsupported", unsupported},
          {"failed", failed},
          {"refused", malformed + unknown + unauthorised + unsupported + failed}};
}

}  // namespace weedspray::fleet
