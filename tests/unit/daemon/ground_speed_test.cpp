// SPDX-License-Identifier: Apache-2.0
// speed.source and the lost-fix rules (daemon/sprayer/ground_speed.hpp), and the alarm they
// raise.
#include "daemon/sprayer/ground_speed.hpp"

#include <gtest/gtest.h>

#include "daemon/config/config.hpp"
#include "daemon/supervision/alarms.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;
using io::GnssFixMode;

GnssSample fix_at(std::chrono::nanoseconds arrived, GnssFixMode mode, double speed) {
  GnssSample s;
  s.value.mode = mode;
  s.value.latitude_deg = 52.0;
  s.value.longitude_deg = 5.0;
  s.value.speed_m_per_s = speed;
  s.sample_time = arrived;
  return s;
}

GroundSpeedInputs inputs(SpeedSource source, bool wheel_wired, bool gnss_usable) {
  GroundSpeedInputs in;
  in.source = source;
  in.wheel_wired = wheel_wired;
  in.wheel_speed_m_per_s = 1.9;
  in.fixed_speed_m_per_s = 1.0;
  in.gnss_usable = gnss_usable;
  in.gnss_speed_m_per_s = 2.1;
  return in;
}

TEST(GroundSpeed, ParsesEveryConfiguredSourceAndRejectsOthers) {
  for (const auto source : {SpeedSource::kWheel, SpeedSource::kGnss, SpeedSource::kFixed}) {
    EXPECT_EQ(parse_speed_source(to_string(source)), source);
  }
  EXPECT_FALSE(parse_speed_source("radar"));
}

TEST(GroundSpeed, WheelSourceIsTheWheelsPulsesOrItsFixedSpeed) {
  GroundSpeed s = select_ground_speed(inputs(SpeedSource::kWheel, true, true));
  EXPECT_DOUBLE_EQ(s.speed_m_per_s, 1.9);
  EXPECT_EQ(s.used, SpeedSource::kWheel);
  EXPECT_FALSE(s.fell_back);
  s = select_ground_speed(inputs(SpeedSource::kWheel, false, true));  // wheel.source = fixed
  EXPECT_DOUBLE_EQ(s.speed_m_per_s, 1.0);
  EXPECT_EQ(s.used, SpeedSource::kFixed);
}

TEST(GroundSpeed, FixedSourceIgnoresAWiredWheelAndTheReceiver) {
  const GroundSpeed s = select_ground_speed(inputs(SpeedSource::kFixed, true, true));
  EXPECT_DOUBLE_EQ(s.speed_m_per_s, 1.0);
  EXPECT_EQ(s.used, SpeedSource::kFixed);
}

TEST(GroundSpeed, GnssSourceUsesAUsableFix) {
  const GroundSpeed s = select_ground_speed(inputs(SpeedSource::kGnss, true, true));
  EXPECT_DOUBLE_EQ(s.speed_m_per_s, 2.1);
  EXPECT_EQ(s.used, SpeedSource::kGnss);
  EXPECT_FALSE(s.fell_back);
}

TEST(GroundSpeed, LostFixFallsBackToTheWheelElseTheFixedSpeed) {
  GroundSpeed s = select_ground_speed(inputs(SpeedSource::kGnss, true, false));
  EXPECT_DOUBLE_EQ(s.speed_m_per_s, 1.9);
  EXPECT_EQ(s.used, SpeedSource::kWheel);
  EXPECT_TRUE(s.fell_back);
  s = select_ground_speed(inputs(SpeedSource::kGnss, false, false));
  EXPECT_DOUBLE_EQ(s.speed_m_per_s, 1.0);
  EXPECT_EQ(s.used, SpeedSource::kFixed);
  EXPECT_TRUE(s.fell_back);
}

TEST(GnssFix, UsableWhile2dOr3dWithASpeedAndFresh) {
  constexpr auto timeout = 2s;
  EXPECT_TRUE(gnss_fix_usable(fix_at(10s, GnssFixMode::k3D, 2.0), 11s, timeout));
  EXPECT_TRUE(gnss_fix_usable(fix_at(10s, GnssFixMode::k2D, 0.0), 12s, timeout));  // standing
  EXPECT_FALSE(gnss_fix_usable(fix_at(10s, GnssFixMode::k3D, 2.0), 12s + 1ms, timeout));  // old
  EXPECT_FALSE(gnss_fix_usable(fix_at(10s, GnssFixMode::kNone, 2.0), 10s, timeout));      // no fix
  EXPECT_FALSE(gnss_fix_usable(fix_at(10s, GnssFixMode::k3D, io::GnssFix::kUnknown), 10s,
                               timeout));                    // a fix without a speed
  EXPECT_FALSE(gnss_fix_usable(GnssSample{}, 0s, timeout));  // nothing received yet
}

TEST(GnssFix, LostOnceAUsableFixIsTimeoutOldOrTheReceiverSaysNoFix) {
  LostFixWatch watch(100s, 2s, 60s);  // started at 100 s
  const GnssSample good = fix_at(105s, GnssFixMode::k3D, 2.0);
  EXPECT_FALSE(watch.lost(good, 106s));
  EXPECT_FALSE(watch.lost(good, 107s));
  EXPECT_TRUE(watch.lost(good, 107s + 1ms));                            // gpsd went quiet (or away)
  EXPECT_FALSE(watch.lost(fix_at(108s, GnssFixMode::k2D, 2.0), 108s));  // back
  EXPECT_TRUE(watch.lost(fix_at(109s, GnssFixMode::kNone, 0.0), 109s));  // the receiver: no fix
}

TEST(GnssFix, AtStartUpTheFirstFixHasItsOwnTimeout) {
  LostFixWatch watch(100s, 2s, 60s);
  const GnssSample nothing{};               // no fix has arrived
  EXPECT_FALSE(watch.lost(nothing, 130s));  // a cold start: still acquiring
  EXPECT_FALSE(watch.lost(fix_at(140s, GnssFixMode::kNone, 0.0), 150s));  // "no fix" yet
  EXPECT_TRUE(watch.lost(nothing, 160s + 1ms));
  LostFixWatch found(100s, 2s, 60s);
  EXPECT_FALSE(found.lost(fix_at(130s, GnssFixMode::k3D, 0.0), 130s));
  EXPECT_TRUE(found.lost(fix_at(130s, GnssFixMode::k3D, 0.0), 132s + 1ms));  // long before 160 s
}

TEST(GnssFix, LostFixIsAWarningAlarm) {
  AlarmsSection thresholds = default_config().alarms;
  AlarmEvaluator alarms(thresholds);
  AlarmInputs in;
  in.now = 10s;
  in.pressure_valid = true;
  in.gnss_fix_lost = true;
  EXPECT_EQ(alarms.evaluate(in), alarm_bit(AlarmId::kGnssFixLost));
  EXPECT_FALSE(alarms.fault_latched());
  EXPECT_EQ(alarm_name(AlarmId::kGnssFixLost), "gnss_fix_lost");
  in.now = 11s;
  in.gnss_fix_lost = false;  // the fix is back: latched until ClearAlarms
  EXPECT_EQ(alarms.evaluate(in), 0U);
  EXPECT_EQ(alarms.active(), alarm_bit(AlarmId::kGnssFixLost));
  EXPECT_EQ(alarms.present(), 0U);
}

}  // namespace
}  // namespace weedspray::daemon
