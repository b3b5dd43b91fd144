// SPDX-License-Identifier: Apache-2.0
// The broker's commands: parsing, the permission split, replies and counters.
#include <gtest/gtest.h>

#include "fleet/fleet_commands.hpp"

namespace weedspray::fleet {
namespace {

TEST(FleetCommands, OperatorCommandsBecomeTheDaemonsMethods) {
  const auto start = parse_command(R"({"command":"start","id":7})", "operator");
  EXPECT_EQ(start.refusal, Refusal::kNone);
  EXPECT_EQ(start.call.method, "Start");
  EXPECT_FALSE(start.call.argument);
  EXPECT_EQ(start.id, 7);
  const auto pressure = parse_command(R"({"command":"set_pressure","mpa":0.35})", "operator");
  EXPECT_EQ(pressure.refusal, Refusal::kNone);
  EXPECT_EQ(pressure.call.method, "SetPressureSetpoint");
  EXPECT_DOUBLE_EQ(pressure.call.argument.value(), 0.35);
  EXPECT_EQ(parse_command(R"({"command":"stop"})", "operator").call.method, "Stop");
  EXPECT_EQ(parse_command(R"({"command":"clear_alarms"})", "operator").call.method, "ClearAlarms");
}

TEST(FleetCommands, MalformedPayloadsAreRefused) {
  for (const char* payload :
       {"", "start", "[1]", R"({"id":1})", R"({"command":5})", R"({"command":"set_pressure"})",
        R"({"command":"set_pressure","mpa":"high"})"}) {
    SCOPED_TRACE(payload);
    const auto command = parse_command(payload, "admin");
    EXPECT_EQ(command.refusal, Refusal::kMalformed);
    EXPECT_FALSE(command.message.empty());
  }
  EXPECT_EQ(parse_command(std::string(kMaxCommandBytes + 1, ' '), "admin").refusal,
            Refusal::kMalformed);
}

TEST(FleetCommands, UnknownKindsAreRefusedByName) {
  const auto command = parse_command(R"({"command":"self_destruct"})", "admin");
  EXPECT_EQ(command.refusal, Refusal::kUnknown);
  EXPECT_NE(command.message.find("self_destruct"), std::string::npos);
}

TEST(FleetCommands, PermissionMirrorsTheBusGroups) {
  EXPECT_EQ(parse_command(R"({"command":"reload_config"})", "operator").refusal,
            Refusal::kUnauthorised);
  EXPECT_EQ(parse_command(R"({"command":"reload_config"})", "admin").call.method, "ReloadConfig");
  EXPECT_EQ(parse_command(R"({"command":"start"})", "none").refusal, Refusal::kUnauthorised);
  EXPECT_EQ(parse_command(R"({"command":"start"})", "admin").refusal, Refusal::kNone);
}

TEST(FleetCommands, TheRateLawsSettingsAreOperatorCommandsWithTheirNumber) {
  const auto threshold = parse_command(R"({"command":"threshold","value":0.2})", "operator");
  EXPECT_EQ(threshold.refusal, Refusal::kNone);
  EXPECT_EQ(threshold.call.method, "SetDecisionThreshold");
  EXPECT_DOUBLE_EQ(threshold.call.argument.value(), 0.2);
  const auto rate = parse_command(R"({"command":"rate","l_per_ha":150})", "operator");
  EXPECT_EQ(rate.refusal, Refusal::kNone);
  EXPECT_EQ(rate.call.method, "SetTargetRate");
  EXPECT_DOUBLE_EQ(rate.call.argument.value(), 150.0);
  // The range is the daemon's to check: the bridge wants a number under the kind's own name.
  EXPECT_EQ(parse_command(R"({"command":"rate","value":150})", "operator").refusal,
            Refusal::kMalformed);
  EXPECT_EQ(parse_command(R"({"command":"threshold","value":"high"})", "operator").refusal,
            Refusal::kMalformed);
  EXPECT_EQ(parse_command(R"({"command":"rate","l_per_ha":150})", "none").refusal,
            Refusal::kUnauthorised);
}

TEST(FleetCommands, ReplyEchoesIdAndReason) {
  const auto command = parse_command(R"({"command":"start","id":"a1"})", "none");
  const auto reply = command_reply(command, command.refusal, command.message);
  EXPECT_EQ(reply["id"], "a1");
  EXPECT_EQ(reply["command"], "start");
  EXPECT_EQ(reply["ok"], false);
  EXPECT_EQ(reply["reason"], "unauthorised");
}

TEST(FleetCommands, CountersAddUp) {
  CommandCounters counters;
  for (auto refusal : {Refusal::kNone, Refusal::kMalformed, Refusal::kUnauthorised,
                       Refusal::kFailed, Refusal::kNone}) {
    counters.count(refusal);
  }
  const auto json = counters.to_json();
  EXPECT_EQ(json["received"], 5);
  EXPECT_EQ(json["done"], 2);
  EXPECT_EQ(json["malformed"], 1);
  EXPECT_EQ(json["unauthorised"], 1);
  EXPECT_EQ(json["failed"], 1);
  EXPECT_EQ(json["refused"], 3);
}

}  // namespace
}  // namespace weedspray::fleet
