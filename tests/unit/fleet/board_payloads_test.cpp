// SPDX-License-Identifier: Apache-2.0
// The board's topics' payloads from its snapshot.
#include <gtest/gtest.h>

#include "fleet/board_snapshot.hpp"
#include "fleet/topics.hpp"

namespace weedspray::fleet {
namespace {

TEST(FleetPayloads, LitresPerHectareFromFlowSpeedAndWidth) {
  // 6 m at 2 m/s covers 720 m^2 a minute: 7.2 L/min is 100 L/ha.
  EXPECT_NEAR(litres_per_hectare(7.2, 2.0, 6.0), 100.0, 1e-9);
  EXPECT_EQ(litres_per_hectare(7.2, 0.0, 6.0), 0.0);
}

TEST(FleetPayloads, EveryTopicCarriesItsValues) {
  BoardSnapshot s;
  s.state = "Spraying";
  s.nozzle_duty_pct = {10, 0, 90};
  s.pressure_mpa = 0.31;
  s.flow_l_per_min = 3.6;
  s.target_rate_l_per_ha = 150;
  s.decision_threshold = 0.25;
  s.speed_m_per_s = 1.0;
  s.tank_level_pct = 55;
  s.alarms = {{"tank_low", "warning", true, "refill the tank"}};
  const BoardInfo info{"m1", "left", 3, 0.5, 12.0, "operator"};
  const auto payloads = board_payloads(s, info);
  EXPECT_EQ(payloads.at("state")["state"], "Spraying");
  EXPECT_EQ(payloads.at("nozzles")["duty_pct"].size(), 3U);
  EXPECT_DOUBLE_EQ(payloads.at("nozzles")["duty_pct"][2].get<double>(), 90.0);
  EXPECT_DOUBLE_EQ(payloads.at("pressure")["mpa"].get<double>(), 0.31);
  EXPECT_NEAR(payloads.at("flow")["l_per_ha"].get<double>(), 3.6 / (1.0 * 60 * 1.5) * 1e4, 1e-9);
  EXPECT_DOUBLE_EQ(payloads.at("flow")["target_l_per_ha"].get<double>(), 150.0);
  EXPECT_DOUBLE_EQ(payloads.at("nozzles")["decision_threshold"].get<double>(), 0.25);
  EXPECT_DOUBLE_EQ(payloads.at("tank")["level_pct"].get<double>(), 55.0);
  EXPECT_EQ(payloads.at("alarms")["alarms"][0]["remedy"], "refill the tank");
  EXPECT_DOUBLE_EQ(payloads.at("info")["first_nozzle_offset_m"].get<double>(), 12.0);
  for (const char* leaf : {"speed", "health"}) EXPECT_EQ(payloads.count(leaf), 1U) << leaf;
}

TEST(FleetTopics, MachineAndBoardLevels) {
  const Topics topics("m1", "left");
  EXPECT_EQ(topics.board("state"), "weedspray/m1/left/state");
  EXPECT_EQ(topics.machine_commands(), "weedspray/m1/cmd");
  EXPECT_EQ(topics.board_commands(), "weedspray/m1/left/cmd");
  EXPECT_EQ(topics.every_online(), "weedspray/m1/+/online");
  EXPECT_EQ(topics.online_board("weedspray/m1/right/online"), "right");
  EXPECT_FALSE(topics.online_board("weedspray/m2/right/online"));
  EXPECT_FALSE(topics.online_board("weedspray/m1/right/state"));
  EXPECT_FALSE(topics.online_board("weedspray/m1/online"));
}

}  // namespace
}  // namespace weedspray::fleet
