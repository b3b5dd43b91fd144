// SPDX-License-Identifier: Apache-2.0
#include "fleet/motion.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "fleet/topics.hpp"

namespace weedspray::fleet {
namespace {

TEST(Motion, ASampleSurvivesItsPayload) {
  const MotionSample sent{2.25, 1234.5, 98765432101234, {}};
  const auto read = parse_motion(motion_payload(sent).dump());
  ASSERT_TRUE(read);
  EXPECT_EQ(read->speed_m_per_s, 2.25);
  EXPECT_EQ(read->distance_m, 1234.5);
  EXPECT_EQ(read->time_ns, 98765432101234U);
}

TEST(Motion, AFixSurvivesItsPayload) {
  const MotionSample sent{2.25,
                          1234.5,
                          98765432101234,
                          {52.123456789, -4.5, 87.5, 3, 98765000000000, 1782311401250000000}};
  const nlohmann::json payload = motion_payload(sent);
  EXPECT_EQ(payload.at("fix"), 3);
  const auto read = parse_motion(payload.dump());
  ASSERT_TRUE(read);
  EXPECT_EQ(read->fix.latitude_deg, 52.123456789);
  EXPECT_EQ(read->fix.longitude_deg, -4.5);
  EXPECT_EQ(read->fix.heading_deg, 87.5);
  EXPECT_EQ(read->fix.mode, 3U);
  EXPECT_EQ(read->fix.time_ns, 98765000000000U);
  EXPECT_EQ(read->fix.utc_ns, 1782311401250000000);
}

TEST(Motion, WithoutAUsableFixTheSampleStillCarriesTheSpeed) {
  const MotionSample no_fix{1.5, 10.0, 5, {52.0, 5.0, 0.0, 0, 4, 0}};
  EXPECT_FALSE(motion_payload(no_fix).contains("lat")) << "no position without a fix";
  for (
      const char* payload :
      {R"({"m_per_s": 1.5, "distance_m": 10, "t_ns": 5})",
       R"({"m_per_s": 1.5, "distance_m": 10, "t_ns": 5, "lat": 52, "lon": 5, "fix": 0, "fix_t_ns": 4})",
       R"({"m_per_s": 1.5, "distance_m": 10, "t_ns": 5, "lat": 52, "lon": 5, "fix": 3})",
       R"({"m_per_s": 1.5, "distance_m": 10, "t_ns": 5, "lat": 95, "lon": 5, "fix": 3, "fix_t_ns": 4})",
       R"({"m_per_s": 1.5, "distance_m": 10, "t_ns": 5, "lat": "52", "lon": 5, "fix": 3, "fix_t_ns": 4})"}) {
    const auto read = parse_motion(payload);
    ASSERT_TRUE(read) << payload;
    EXPECT_EQ(read->speed_m_per_s, 1.5) << payload;
    EXPECT_FALSE(read->fix.present()) << payload;
  }
  const auto without_heading = parse_motion(
      R"({"m_per_s": 0, "distance_m": 10, "t_ns": 5, "lat": 52, "lon": 5, "fix": 2, "fix_t_ns": 4})");
  ASSERT_TRUE(without_heading);
  EXPECT_TRUE(without_heading->fix.present());
  EXPECT_TRUE(std::isnan(without_heading->fix.heading_deg));
}

TEST(Motion, WhatIsNotASampleIsRefused) {
  for (const char* payload : {"", "not json", "[1, 2, 3]", R"({"m_per_s": 1, "distance_m": 2})",
                              R"({"m_per_s": "1", "distance_m": 2, "t_ns": 3})",
                              R"({"m_per_s": -0.5, "distance_m": 2, "t_ns": 3})",
                              R"({"m_per_s": 1, "distance_m": 2, "t_ns": -3})",
                              R"({"m_per_s": 1, "distance_m": 2, "t_ns": 3.5})"}) {
    EXPECT_FALSE(parse_motion(payload)) << payload;
  }
  EXPECT_FALSE(
      parse_motion(std::string(600, ' ') + R"({"m_per_s": 1, "distance_m": 2, "t_ns": 3})"))
      << "longer than any sample";
}

TEST(Motion, AnotherBoardsTopicIsUnderTheSameMachine) {
  const Topics topics("north", "right");
  EXPECT_EQ(topics.other_board("left", "motion"), "weedspray/north/left/motion");
  EXPECT_EQ(topics.board("motion"), "weedspray/north/right/motion");
}

}  // namespace
}  // namespace weedspray::fleet
