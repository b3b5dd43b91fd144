// SPDX-License-Identifier: Apache-2.0
// The checks of the rate law's settings changed live (SetDecisionThreshold, SetTargetRate):
// the same ranges as the configuration's keys, with the figures in the refusal.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "daemon/config/config.hpp"
#include "daemon/config/config_schema.hpp"
#include "daemon/config/target_rate.hpp"

namespace weedspray::daemon {
namespace {

bool says(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(LiveLawSettings, TheThresholdTakesTheKeysRangeAndNothingElse) {
  EXPECT_EQ(outside_key_range("spray.decision_threshold", 0.0), "");
  EXPECT_EQ(outside_key_range("spray.decision_threshold", 0.25), "");
  EXPECT_EQ(outside_key_range("spray.decision_threshold", 1.0), "");
  const std::string above = outside_key_range("spray.decision_threshold", 1.5);
  EXPECT_TRUE(says(above, "1.5 outside spray.decision_threshold's range 0..1")) << above;
  EXPECT_NE(outside_key_range("spray.decision_threshold", -0.1), "");
  EXPECT_NE(outside_key_range("spray.decision_threshold", std::nan("")), "");
  EXPECT_THROW((void)outside_key_range("spray.no_such_key", 0.5), std::out_of_range);
}

TEST(LiveLawSettings, ADoseGivesItsNozzleFlowWithinTheNozzlesRange) {
  const Config config = load_config_from_strings({{"test.toml", ""}});
  // 150 L/ha over 0.5 m at 1 m/s: 150 / 10000 x 60 x 0.5 x 1 = 0.45 L/min per nozzle.
  const RateFlow fits = flow_for_target_rate(config, 150.0);
  EXPECT_EQ(fits.refusal, "");
  EXPECT_NEAR(fits.flow_l_per_min, 0.45, 1e-12);
  EXPECT_NEAR(rate_for_nozzle_flow(fits.flow_l_per_min, config.boom.nozzle_width_m,
                                   config.spray.nominal_speed_m_per_s),
              150.0, 1e-9);
}

TEST(LiveLawSettings, ADoseNoNozzleCanGiveIsRefusedWithTheFigures) {
  const Config config = load_config_from_strings({{"test.toml", ""}});
  // 5000 L/ha: 15 L/min per nozzle (within 0.01..20); 10000 L/ha: 30 L/min.
  EXPECT_EQ(flow_for_target_rate(config, 5000.0).refusal, "");
  const std::string too_much = flow_for_target_rate(config, 10000.0).refusal;
  EXPECT_TRUE(says(too_much, "needs 30 L/min per nozzle, outside the nozzles' 0.01..20 L/min"))
      << too_much;
  EXPECT_NE(flow_for_target_rate(config, 0.0).refusal, "") << "no dose at all";
  EXPECT_NE(flow_for_target_rate(config, -100.0).refusal, "");
  EXPECT_NE(flow_for_target_rate(config, std::nan("")).refusal, "");
}

}  // namespace
}  // namespace weedspray::daemon
