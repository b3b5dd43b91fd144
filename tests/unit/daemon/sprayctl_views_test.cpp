// SPDX-License-Identifier: Apache-2.0
// What sprayctl prints from the daemon's values: the live view's frame, the text of
// structures, units and timestamps.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <sstream>

#include "daemon/sprayctl/value_text.hpp"
#include "daemon/sprayctl/views.hpp"

namespace weedspray::sprayctl {
namespace {

// 2026-11-28T15:40:12.345Z
const auto kTime = std::chrono::system_clock::time_point(std::chrono::milliseconds(1795880412345));

Properties spraying_boom() {
  return {{"State", "Spraying"},
          {"Mode", "sim"},
          {"Pressure", 0.3},
          {"PressureSetpoint", 0.3},
          {"Flow", 2.5},
          {"Speed", 1.5},
          {"SpeedSource", "wheel"},
          {"TankLevel", 80.0},
          {"VolumeSprayed", 100.0},
          {"AreaCovered", 5000.0},
          {"NozzleDuty", Value::array({0.0, 50.0, 100.0})},
          {"NozzleHealth", Value::array({1.0, 0.82})},
          {"AlarmDetails", Value::array({{{"name", "no_flow"},
                                          {"severity", "fault"},
                                          {"present", true},
                                          {"remedy", "Check the tank."}},
                                         {{"name", "tank_low"},
                                          {"severity", "warning"},
                                          {"present", false},
                                          {"remedy", "Fill the tank."}}})}};
}

TEST(SprayctlTop, ShowsEachNozzlesDutyAsABarWithItsHealth) {
  const std::string frame = top_frame(spraying_boom(), kTime);
  EXPECT_NE(frame.find("   0    [                              ]    0 %  1.00\n"),
            std::string::npos)
      << frame;
  EXPECT_NE(frame.find("   1    [###############               ]   50 %  0.82\n"),
            std::string::npos)
      << frame;
  // No health figure for the third nozzle: shown as off, not as a number.
  EXPECT_NE(frame.find("   2    [##############################]  100 %  off\n"), std::string::npos)
      << frame;
}

TEST(SprayctlTop, ShowsTheJobsDoseInLitresPerHectare) {
  // 100 L on 5000 m^2 = 200 L/ha.
  EXPECT_NE(top_frame(spraying_boom(), kTime).find("Applied  200.0 L/ha over the job"),
            std::string::npos);
  Properties nothing_covered = spraying_boom();
  nothing_covered["AreaCovered"] = 0.0;
  EXPECT_NE(top_frame(nothing_covered, kTime).find("Applied  - L/ha"), std::string::npos);
}

TEST(SprayctlTop, ShowsTheRateNowAndADashWhileStanding) {
  Properties moving = spraying_boom();
  moving["ApplicationRate"] = 166.66;
  moving["TargetRate"] = 205.0;
  EXPECT_NE(top_frame(moving, kTime).find("Rate     166.7 L/ha now over the boom (205 L/ha"),
            std::string::npos)
      << top_frame(moving, kTime);
  Properties standing = moving;
  standing["ApplicationRate"] = std::nan("");
  EXPECT_NE(top_frame(standing, kTime).find("Rate     - L/ha now"), std::string::npos);
  std::ostringstream status;
  print_status(status, standing, false, kTime);
  EXPECT_NE(status.str().find("Rate:          - (standing) L/ha now over the boom (dose at full "
                              "weed cover 205.0 L/ha)"),
            std::string::npos)
      << status.str();
}

TEST(SprayctlTop, TellsActiveAlarmsFromLatchedOnesWithWhatToDo) {
  const std::string frame = top_frame(spraying_boom(), kTime);
  EXPECT_NE(frame.find("  ACTIVE  no_flow (fault): Check the tank.\n"), std::string::npos) << frame;
  EXPECT_NE(frame.find("  latched tank_low (warning): Fill the tank.\n"), std::string::npos)
      << frame;
  Properties quiet = spraying_boom();
  quiet["AlarmDetails"] = Value::array();
  EXPECT_NE(top_frame(quiet, kTime).find("Alarms   none\n"), std::string::npos);
}

TEST(SprayctlText, StructuresReadAsSentences) {
  EXPECT_EQ(
      text_value("Estop",
                 {{"circuit_closed", false}, {"latched", true}, {"last_reaction_ms", 1.5}}),
      "circuit OPEN, LATCHED: valves closed, pump off; last trip safe 1.500 ms after the edge");
  EXPECT_EQ(text_value("MeterCalibration", {{"source", "calibration"},
                                            {"pulses_per_litre", 8670.0},
                                            {"configured_pulses_per_litre", 8500.0},
                                            {"configured_error_pct", -1.96}}),
            "8670.0 pulses/L (calibration; configured 8500.0, its error -1.96 %)");
  EXPECT_EQ(text_value("NozzleDuty", Value::array({12.3456, -0.0001})), "12.346 0.000");
  EXPECT_EQ(text_value("Alarms", Value::array()), "none");
  EXPECT_EQ(text_value("NozzleHealth", Value::array()), "");
}

TEST(SprayctlJson, StatusCarriesItsTimeAndEveryUnit) {
  std::ostringstream out;
  print_status(out, spraying_boom(), true, kTime);
  const Value status = Value::parse(out.str());
  EXPECT_EQ(status["timestamp"], "2026-11-28T15:40:12.345Z");
  EXPECT_EQ(status["units"]["Pressure"], "MPa");
  EXPECT_EQ(status["units"]["Flow"], "L/min");
  EXPECT_EQ(status["Pressure"], 0.3);
  EXPECT_TRUE(status["AlarmDetails"][0]["present"].get<bool>());
}

TEST(SprayctlJson, MonitorEventsCarryTimeAndUnit) {
  std::ostringstream json;
  print_event(json, "property", "Flow", 2.5, true, kTime);
  EXPECT_EQ(json.str(),
            "{\"event\":\"property\",\"name\":\"Flow\",\"timestamp\":\"2026-11-28T15:40:12.345Z\","
            "\"unit\":\"L/min\",\"value\":2.5}\n");
}

}  // namespace
}  // namespace weedspray::sprayctl
