// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include "daemon/supervision/alarm_catalog.hpp"
#include "daemon/supervision/alarms.hpp"

#include <set>
#include <string>

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

AlarmsSection thresholds() {
  const Config c = default_config();
  return c.alarms;  // over 0.9 MPa, blocked 0.7 MPa / 0.05 L/min, debounce 1 s ...
}

// Spraying normally: nothing wrong.
AlarmInputs healthy(std::chrono::nanoseconds now) {
  AlarmInputs in;
  in.now = now;
  in.spraying = true;
  in.pump_commanded = true;
  in.open_fraction = 0.5;
  in.pressure_valid = true;
  in.pressure_mpa = 0.4;
  in.sensor_current_ma = 10.4;
  in.flow_l_per_min = 2.0;
  in.tank_enabled = true;
  in.tank_valid = true;
  in.tank_level_pct = 80;
  in.tank_last_ok = now;
  in.camera_expected = true;
  in.last_frame_time = now;
  in.speed_m_per_s = 1.0;
  in.vision_latency_s = 0.002;
  in.lead_distance_m = 1.4;
  return in;
}

std::chrono::nanoseconds from_s(double s) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(s));
}

// Moves the clock of `in` to t with the camera and tank sensor still fresh.
AlarmInputs at(AlarmInputs in, std::chrono::nanoseconds t) {
  in.now = in.last_frame_time = in.tank_last_ok = t;
  return in;
}

TEST(Alarms, HealthyRaisesNothing) {
  AlarmEvaluator alarms(thresholds());
  for (int i = 0; i < 100; ++i) EXPECT_EQ(alarms.evaluate(healthy(i * 50ms)), 0U);
  EXPECT_EQ(alarms.active(), 0U);
}

TEST(Alarms, OverPressureIsImmediateAndAFault) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(1s);
  in.pressure_mpa = 0.95;
  EXPECT_EQ(alarms.evaluate(in), alarm_bit(AlarmId::kOverPressure));
  EXPECT_TRUE(alarms.fault_latched());
  // Latched: the pressure falling back does not clear it, and it is not raised twice.
  EXPECT_EQ(alarms.evaluate(healthy(2s)), 0U);
  EXPECT_EQ(alarms.active(), alarm_bit(AlarmId::kOverPressure));
  EXPECT_EQ(alarms.clear(), alarm_bit(AlarmId::kOverPressure));
  EXPECT_FALSE(alarms.fault_latched());
}

TEST(Alarms, TripFromThePressureLoopCounts) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(1s);
  in.over_pressure_trip = true;
  EXPECT_EQ(alarms.evaluate(in), alarm_bit(AlarmId::kOverPressure));
}

TEST(Alarms, SensorFaultLatchesOnceItLasts) {
  AlarmEvaluator alarms(thresholds());  // sensor_fault_hold_s 0.15 s
  auto in = healthy(1s);
  in.pressure_valid = false;
  in.sensor_current_ma = 0.0;
  EXPECT_EQ(alarms.evaluate(in), 0U) << "the first bad reading only stops the pump";
  EXPECT_EQ(alarms.evaluate(at(in, 1100ms)), 0U);
  EXPECT_EQ(alarms.evaluate(at(in, 1200ms)), alarm_bit(AlarmId::kPressureSensorFault));
  EXPECT_TRUE(is_fault(AlarmId::kPressureSensorFault));
}

TEST(Alarms, OneBadSensorReadingDoesNotLatchFault) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(1s);
  in.pressure_valid = false;
  EXPECT_EQ(alarms.evaluate(in), 0U);
  in.pressure_valid = true;
  EXPECT_EQ(alarms.evaluate(at(in, 1050ms)), 0U);
  in.pressure_valid = false;
  EXPECT_EQ(alarms.evaluate(at(in, 1100ms)), 0U) << "the hold restarts after a good reading";
  EXPECT_FALSE(alarms.fault_latched());
}

TEST(Alarms, LineBlockedNeedsTheDebounce) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(0s);
  in.pressure_mpa = 0.8;
  in.flow_l_per_min = 0.0;
  EXPECT_EQ(alarms.evaluate(in), 0U);
  EXPECT_EQ(alarms.evaluate(at(in, 900ms)), 0U);
  EXPECT_EQ(alarms.evaluate(at(in, 1100ms)), alarm_bit(AlarmId::kLineBlocked));
}

TEST(Alarms, AShortGlitchDoesNotRaise) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(0s);
  in.flow_l_per_min = 0.0;
  EXPECT_EQ(alarms.evaluate(in), 0U);
  EXPECT_EQ(alarms.evaluate(healthy(500ms)), 0U);  // flow back: timer reset
  EXPECT_EQ(alarms.evaluate(at(in, 1200ms)), 0U);
  EXPECT_EQ(alarms.evaluate(at(in, 2300ms)), alarm_bit(AlarmId::kNoFlow));
}

TEST(Alarms, NoFlowOnlyWhileValvesOpen) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(0s);
  in.spraying = false;
  in.pump_commanded = false;
  in.flow_l_per_min = 0.0;
  for (int i = 0; i < 60; ++i) EXPECT_EQ(alarms.evaluate(at(in, i * 100ms)), 0U);
}

// A calibration runs the pump in Idle with its own valves open (a catch test: all of them):
// the line monitors judge it as they judge spraying.
TEST(Alarms, NoFlowAndLineBlockedDuringACalibration) {
  auto in = healthy(0s);
  in.spraying = false;
  in.camera_expected = false;
  in.pump_commanded = true;
  in.open_fraction = 1.0;
  in.flow_l_per_min = 0.0;
  {
    AlarmEvaluator alarms(thresholds());
    EXPECT_EQ(alarms.evaluate(in), 0U);
    EXPECT_EQ(alarms.evaluate(at(in, 1100ms)), alarm_bit(AlarmId::kNoFlow));
    EXPECT_TRUE(alarms.fault_latched());
  }
  in.pressure_mpa = 0.8;
  {
    AlarmEvaluator alarms(thresholds());
    EXPECT_EQ(alarms.evaluate(in), 0U);
    EXPECT_EQ(alarms.evaluate(at(in, 1100ms)), alarm_bit(AlarmId::kLineBlocked));
    EXPECT_TRUE(alarms.fault_latched());
  }
}

// A valve that leaks or sticks open: flow through the meter with every valve commanded closed,
// judged once the line has drained (closed_flow_settle_s), then after the debounce.
TEST(Alarms, FlowWithEveryValveClosedIsAFault) {
  const AlarmsSection t = thresholds();
  auto in = healthy(0s);
  in.open_fraction = 0.0;
  in.flow_l_per_min = t.closed_flow_l_per_min * 3;
  in.valves_closed_s = t.closed_flow_settle_s * 0.9;  // still draining
  AlarmEvaluator alarms(t);
  for (int i = 0; i < 40; ++i) EXPECT_EQ(alarms.evaluate(at(in, i * 100ms)), 0U);
  in.valves_closed_s = t.closed_flow_settle_s;
  EXPECT_EQ(alarms.evaluate(at(in, 4s)), 0U);
  EXPECT_EQ(alarms.evaluate(at(in, 4s + from_s(t.debounce_s) + 50ms)),
            alarm_bit(AlarmId::kFlowValvesClosed));
  EXPECT_TRUE(alarms.fault_latched());
  EXPECT_EQ(alarm_name(AlarmId::kFlowValvesClosed), "flow_with_valves_closed");
}

TEST(Alarms, NoClosedValveFaultBelowItsFlowOrWithAValveOpen) {
  const AlarmsSection t = thresholds();
  auto in = healthy(0s);
  in.open_fraction = 0.0;
  in.valves_closed_s = 60;
  in.flow_l_per_min = t.closed_flow_l_per_min * 0.9;  // meter noise, a drip
  AlarmEvaluator alarms(t);
  for (int i = 0; i < 60; ++i) EXPECT_EQ(alarms.evaluate(at(in, i * 100ms)), 0U);
  in.valves_closed_s = 0;  // spraying normally: a valve open
  in.open_fraction = 0.5;
  in.flow_l_per_min = 2.0;
  for (int i = 60; i < 120; ++i) EXPECT_EQ(alarms.evaluate(at(in, i * 100ms)), 0U);
}

TEST(Alarms, TankLowThenEmpty) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(0s);
  in.tank_level_pct = 10;
  alarms.evaluate(in);
  EXPECT_EQ(alarms.evaluate(at(in, 1500ms)), alarm_bit(AlarmId::kTankLow));
  EXPECT_FALSE(alarms.fault_latched());
  in.tank_level_pct = 1;
  alarms.evaluate(at(in, 2s));
  EXPECT_EQ(alarms.evaluate(at(in, 3100ms)), alarm_bit(AlarmId::kTankEmpty));
  EXPECT_TRUE(alarms.fault_latched());
}

TEST(Alarms, ModbusSilent) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(10s);
  in.tank_last_ok = 4s;
  EXPECT_EQ(alarms.evaluate(in), alarm_bit(AlarmId::kModbusSilent));
}

TEST(Alarms, CameraLostAllowsForGroundPacing) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(10s);
  in.last_frame_time = 8500ms;  // 1.5 s: lost at 30 fps ...
  EXPECT_EQ(alarms.evaluate(in), alarm_bit(AlarmId::kCameraLost));
  AlarmEvaluator paced(thresholds());
  in.expected_frame_interval_s = 1.0;  // ... but not when a frame is due every metre at 1 m/s
  EXPECT_EQ(paced.evaluate(in), 0U);
}

TEST(Alarms, VisionTooSlow) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(1s);
  in.vision_latency_s = 1.0;  // at 2 m/s the patch passes the nozzles before it is planned
  in.speed_m_per_s = 2.0;
  EXPECT_EQ(alarms.evaluate(in), alarm_bit(AlarmId::kVisionTooSlow));
  AlarmEvaluator gaps(thresholds());
  auto g = healthy(1s);
  g.coverage_gap = true;
  EXPECT_EQ(gaps.evaluate(g), alarm_bit(AlarmId::kVisionTooSlow));
  EXPECT_FALSE(is_fault(AlarmId::kVisionTooSlow));
}

TEST(Alarms, ControlOverruns) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(1s);
  in.overruns_last_second = 10;
  EXPECT_EQ(alarms.evaluate(in), alarm_bit(AlarmId::kControlOverruns));
}

// A warning, not a fault: the failing camera's nozzles close, the others keep spraying.
TEST(Alarms, VisionModelFailedIsAWarningUntilCleared) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(1s);
  in.vision_model_failed = true;
  EXPECT_EQ(alarms.evaluate(in), alarm_bit(AlarmId::kVisionModelFailed));
  EXPECT_FALSE(alarms.fault_latched());
  EXPECT_EQ(alarm_name(AlarmId::kVisionModelFailed), "vision_model_failed");
  in = at(in, 2s);
  in.vision_model_failed = false;  // frames process again: latched until ClearAlarms
  EXPECT_EQ(alarms.evaluate(in), 0U);
  EXPECT_EQ(alarms.active(), alarm_bit(AlarmId::kVisionModelFailed));
  EXPECT_EQ(alarms.present(), 0U);
}

// Records are no safety function: a warning, and it clears itself once the lines are written
// again and space is above the floor (the held lines catch up by themselves).
TEST(Alarms, RecordsDiskFullIsAWarningThatClearsItself) {
  AlarmEvaluator alarms(thresholds());
  EXPECT_EQ(alarm_name(AlarmId::kRecordsDiskFull), "records_disk_full");
  auto in = healthy(1s);
  EXPECT_EQ(alarms.evaluate(in), 0U);
  in.records_at_risk = true;
  EXPECT_EQ(alarms.evaluate(at(in, 2s)), alarm_bit(AlarmId::kRecordsDiskFull));
  EXPECT_FALSE(alarms.fault_latched());
  EXPECT_EQ(alarms.evaluate(at(in, 3s)), 0U) << "raised once";
  EXPECT_EQ(alarms.cleared_by_itself(), 0U);
  in.records_at_risk = false;
  EXPECT_EQ(alarms.evaluate(at(in, 4s)), 0U);
  EXPECT_EQ(alarms.cleared_by_itself(), alarm_bit(AlarmId::kRecordsDiskFull));
  EXPECT_EQ(alarms.active(), 0U);
  EXPECT_EQ(alarms.evaluate(at(in, 5s)), 0U);
  EXPECT_EQ(alarms.cleared_by_itself(), 0U) << "cleared once";
  in.records_at_risk = true;
  EXPECT_EQ(alarms.evaluate(at(in, 6s)), alarm_bit(AlarmId::kRecordsDiskFull)) << "again";
}

// No exit watcher: a fault at once (after a kill -9 only ExecStopPost would close the valves).
TEST(Alarms, ALostExitWatcherIsAFaultAtOnce) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(1s);
  EXPECT_EQ(alarms.evaluate(in), 0U);
  in.exit_watcher_lost = true;
  EXPECT_EQ(alarms.evaluate(at(in, 2s)), alarm_bit(AlarmId::kExitWatcherLost));
  EXPECT_TRUE(alarms.fault_latched());
  EXPECT_EQ(alarm_name(AlarmId::kExitWatcherLost), "exit_watcher_lost");
}

// The shared speed lost: a fault at once, latched after the samples return until ClearAlarms.
TEST(Alarms, ALostSharedSpeedIsAFaultAtOnceAndStaysUntilCleared) {
  AlarmEvaluator alarms(thresholds());
  auto in = healthy(1s);
  EXPECT_EQ(alarms.evaluate(in), 0U);
  in.shared_speed_lost = true;
  EXPECT_EQ(alarms.evaluate(at(in, 2s)), alarm_bit(AlarmId::kSharedSpeedLost));
  EXPECT_TRUE(alarms.fault_latched());
  in.shared_speed_lost = false;
  EXPECT_EQ(alarms.evaluate(at(in, 3s)), 0U);
  EXPECT_TRUE(alarms.fault_latched()) << "samples back: still latched until cleared";
  alarms.clear();
  EXPECT_EQ(alarms.evaluate(at(in, 4s)), 0U);
  EXPECT_FALSE(alarms.fault_latched());
  EXPECT_EQ(alarm_name(AlarmId::kSharedSpeedLost), "shared_speed_lost");
}

// Only records_disk_full clears itself: the others wait for ClearAlarms.
TEST(Alarms, OnlyRecordsDiskFullAndNozzleOffCalibrationClearThemselves) {
  for (std::size_t i = 0; i < kAlarmCount; ++i) {
    const auto id = static_cast<AlarmId>(i);
    EXPECT_EQ(clears_itself(id),
              id == AlarmId::kRecordsDiskFull || id == AlarmId::kNozzleOffCalibration)
        << alarm_name(id);
  }
}

// The re-check's warning: raised while its last reading of a nozzle is off, cleared by the
// next reading within the calibration; never a fault.
TEST(Alarms, NozzleOffCalibrationIsAWarningTheNextGoodReadingClears) {
  AlarmEvaluator alarms(thresholds());
  EXPECT_EQ(alarm_name(AlarmId::kNozzleOffCalibration), "nozzle_off_calibration");
  auto in = healthy(1s);
  EXPECT_EQ(alarms.evaluate(in), 0U);
  in.nozzle_off_calibration = true;
  EXPECT_EQ(alarms.evaluate(at(in, 2s)), alarm_bit(AlarmId::kNozzleOffCalibration));
  EXPECT_FALSE(alarms.fault_latched());
  in.nozzle_off_calibration = false;
  EXPECT_EQ(alarms.evaluate(at(in, 3s)), 0U);
  EXPECT_EQ(alarms.cleared_by_itself(), alarm_bit(AlarmId::kNozzleOffCalibration));
  EXPECT_EQ(alarms.active(), 0U);
}

// The meter and the calibrated nozzles more than 5 % apart for 30 s (the defaults) ask for a
// recalibration: a warning, in any state (the average is held between sprays), and a shorter
// excursion raises nothing.
TEST(Alarms, CalibrationDriftWhenTheMeterAndTheNozzlesStayApart) {
  AlarmEvaluator alarms(thresholds());
  EXPECT_EQ(alarm_name(AlarmId::kCalibrationDrift), "calibration_drift");
  auto in = healthy(1s);
  in.calibration_ratio = 0.96;  // 4 %: within the band
  for (int s = 1; s <= 100; ++s) EXPECT_EQ(alarms.evaluate(at(in, s * 1s)), 0U) << s;
  in.calibration_ratio = 1.07;  // 20 s off, back, 20 s off: never 30 s in a row
  for (int s = 101; s <= 120; ++s) EXPECT_EQ(alarms.evaluate(at(in, s * 1s)), 0U) << s;
  in.calibration_ratio = 1.02;
  EXPECT_EQ(alarms.evaluate(at(in, 121s)), 0U);
  in.calibration_ratio = 0.93;
  for (int s = 122; s <= 150; ++s) EXPECT_EQ(alarms.evaluate(at(in, s * 1s)), 0U) << s;
  in.spraying = false;  // stopped: the correction stays, and so does the condition
  in.open_fraction = 0;
  EXPECT_EQ(alarms.evaluate(at(in, 152s)), alarm_bit(AlarmId::kCalibrationDrift));
  EXPECT_FALSE(alarms.fault_latched());
  // Latched until cleared; raised again after another hold while the drift remains.
  EXPECT_EQ(alarms.clear(), alarm_bit(AlarmId::kCalibrationDrift));
  EXPECT_EQ(alarms.evaluate(at(in, 160s)), 0U);
  EXPECT_EQ(alarms.evaluate(at(in, 190s)), alarm_bit(AlarmId::kCalibrationDrift));
}

// A latched E-stop is a Fault at the first evaluation (its reaction already ran), and stays
// raised after a ClearAlarms while the stop is still latched.
TEST(Alarms, ALatchedEstopIsAFaultAtOnce) {
  auto in = healthy(0s);
  in.estop_latched = true;
  AlarmEvaluator alarms(thresholds());
  EXPECT_EQ(alarms.evaluate(at(in, 0s)), alarm_bit(AlarmId::kEstop));
  EXPECT_TRUE(alarms.fault_latched());
  EXPECT_EQ(alarm_name(AlarmId::kEstop), "estop");
  alarms.clear();
  EXPECT_EQ(alarms.evaluate(at(in, 1s)), alarm_bit(AlarmId::kEstop));
  in.estop_latched = false;
  alarms.clear();
  EXPECT_EQ(alarms.evaluate(at(in, 2s)), 0U);
  EXPECT_FALSE(alarms.fault_latched());
}

TEST(Alarms, NamesRoundTrip) {
  for (std::size_t i = 0; i < kAlarmCount; ++i) {
    const auto id = static_cast<AlarmId>(i);
    EXPECT_EQ(parse_alarm(alarm_name(id)), id);
  }
  EXPECT_FALSE(parse_alarm("nope"));
}

// Every alarm has its own journal MESSAGE_ID (32 lower-case hex digits, as sd-id128 writes
// them), a meaning and a remedy; its severity follows is_fault.
TEST(AlarmCatalog, EveryAlarmHasItsOwnIdAMeaningAndARemedy) {
  std::set<std::string_view> ids;
  for (std::size_t i = 0; i < kAlarmCount; ++i) {
    const auto id = static_cast<AlarmId>(i);
    const AlarmCatalogEntry& e = alarm_catalog_entry(id);
    EXPECT_EQ(e.message_id.size(), 32U) << alarm_name(id);
    EXPECT_EQ(e.message_id.find_first_not_of("0123456789abcdef"), std::string_view::npos)
        << alarm_name(id);
    EXPECT_TRUE(ids.insert(e.message_id).second) << alarm_name(id) << " shares its id";
    EXPECT_GT(e.meaning.size(), 20U) << alarm_name(id);
    EXPECT_GT(e.remedy.size(), 10U) << alarm_name(id);
    EXPECT_EQ(alarm_severity(id), is_fault(id) ? "fault" : "warning");
  }
  const std::string catalog = journal_catalog();
  EXPECT_NE(catalog.find("-- 6f28571a2c6746e198c507f3265366f3\nSubject: alarm "
                         "pressure_sensor_fault (fault)\n"),
            std::string::npos);
}

}  // namespace
}  // namespace weedspray::daemon
