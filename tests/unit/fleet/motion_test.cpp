// SPDX-License-Identifier: Apache-2.0
#include "fleet/motion.hpp"

#include <gtest/gtest.h>

#include "fleet/topics.hpp"

namespace weedspray::fleet {
namespace {

TEST(Motion, ASampleSurvivesItsPayload) {
  const MotionSample sent{2.25, 1234.5, 98765432101234};
  const auto read = parse_motion(motion_payload(sent).dump());
  ASSERT_TRUE(read);
  EXPECT_EQ(read->speed_m_per_s, 2.25);
  EXPECT_EQ(read->distance_m, 1234.5);
  EXPECT_EQ(read->time_ns, 98765432101234U);
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
      parse_motion(std::string(300, ' ') + R"({"m_per_s": 1, "distance_m": 2, "t_ns": 3})"))
      << "longer than any sample";
}

TEST(Motion, AnotherBoardsTopicIsUnderTheSameMachine) {
  const Topics topics("north", "right");
  EXPECT_EQ(topics.other_board("left", "motion"), "weedspray/north/left/motion");
  EXPECT_EQ(topics.board("motion"), "weedspray/north/right/motion");
}

}  // namespace
}  // namespace weedspray::fleet
