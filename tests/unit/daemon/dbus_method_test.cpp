// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <array>
#include <cstdarg>
#include <stdexcept>

#include "daemon/bus/dbus_service.hpp"
#include "tests/fuzz/offline_bus.hpp"

namespace weedspray::daemon {
namespace {

class RecordingHandler final : public CommandHandler {
 public:
  CommandResult start() override {
    ++starts;
    if (throw_on_start) throw std::runtime_error("boom");
    return {};
  }
  CommandResult stop() override { return {}; }
  CommandResult set_pressure_setpoint(double mpa) override {
    setpoint = mpa;
    return mpa > 0 ? CommandResult{} : CommandResult{kErrorInvalidArgument, "not positive"};
  }
  CommandResult set_decision_threshold(double value) override {
    threshold = value;
    return {};
  }
  CommandResult set_target_rate(double l_per_ha) override {
    rate_l_per_ha = l_per_ha;
    return l_per_ha > 0 ? CommandResult{} : CommandResult{kErrorInvalidArgument, "no dose"};
  }
  CommandResult reload_config(ReloadReply) override { throw 42; }  // not even a std::exception
  CommandResult clear_alarms() override { return {}; }
  CommandResult inject_sim_fault(const std::string& name) override {
    fault = name;
    return {};
  }
  CommandResult snapshot(std::uint32_t camera, SnapshotReply reply) override {
    snapshot_camera = camera;
    if (camera > 0) return {kErrorRateLimited, "at most 2 a second"};
    snapshot_reply = std::move(reply);
    return {};
  }
  CommandResult calibrate_wheel(double run_distance_m, std::uint64_t& request) override {
    if (run_distance_m < 10) return {kErrorInvalidArgument, "too short"};
    request = 7;
    return {};
  }
  CommandResult start_catch_test(double seconds) override {
    catch_test_s = seconds;
    return {};
  }
  CommandResult calibrate_meter(double volume_l) override {
    meter_volume_l = volume_l;
    return {};
  }
  CommandResult calibrate_nozzles() override {
    ++nozzle_calibrations;
    return {kErrorNotPermitted, "spraying"};
  }
  CommandResult test_valve(std::uint32_t nozzle, double duty_pct, double seconds) override {
    tested_valve = {static_cast<double>(nozzle), duty_pct, seconds};
    return {};
  }
  CommandResult test_pump(double seconds) override {
    pump_test_s = seconds;
    return {};
  }
  CommandResult motion(double& speed_m_per_s, double& distance_m, std::uint64_t& time_ns,
                       SharedFix& fix) override {
    speed_m_per_s = 1.5;
    distance_m = 12.25;
    time_ns = 123456789;
    fix = {52.5, 5.25, 90.0, io::GnssFixMode::k3D, 123000000, 1782311401000000000};
    return {};
  }
  CommandResult feed_shared_motion(double speed_m_per_s, double distance_m,
                                   std::uint64_t sender_time_ns, const SharedFix& fix) override {
    shared_motion = {speed_m_per_s, distance_m, static_cast<double>(sender_time_ns)};
    shared_fix = fix;
    return {};
  }
  SharedFix shared_fix;
  std::array<double, 3> shared_motion{-1, -1, -1};
  void bus_lost() override {}
  std::array<double, 3> tested_valve{-1, -1, -1};
  double pump_test_s = -1;
  double catch_test_s = -1;
  double meter_volume_l = -1;
  int nozzle_calibrations = 0;
  std::int64_t snapshot_camera = -1;
  SnapshotReply snapshot_reply;
  int starts = 0;
  bool throw_on_start = false;
  double setpoint = -1;
  double threshold = -1;
  double rate_l_per_ha = -1;
  std::string fault;
};

class DbusMethodTest : public ::testing::Test {
 protected:
  int call(const char* member, const char* types = "", ...) {
    sd_bus_message* m = bus_.call(member);
    if (*types != '\0') {
      va_list args;
      va_start(args, types);
      EXPECT_GE(sd_bus_message_appendv(m, types, args), 0);
      va_end(args);
    }
    EXPECT_GE(testing::OfflineBus::seal(m), 0);
    sd_bus_error_free(&error_);
    const int r = handle_method_call(m, handler_, &error_);
    sd_bus_message_unref(m);
    return r;
  }
  std::string error_name() const { return error_.name != nullptr ? error_.name : ""; }
  std::string error_message() const { return error_.message != nullptr ? error_.message : ""; }
  void TearDown() override { sd_bus_error_free(&error_); }

  testing::OfflineBus bus_;
  RecordingHandler handler_;
  sd_bus_error error_ = SD_BUS_ERROR_NULL;
};

TEST_F(DbusMethodTest, CallsTheHandlerWithItsArgument) {
  call("SetPressureSetpoint", "d", 0.35);
  EXPECT_DOUBLE_EQ(handler_.setpoint, 0.35);
  call("InjectSimFault", "s", "sensor_open");
  EXPECT_EQ(handler_.fault, "sensor_open");
}

TEST_F(DbusMethodTest, TheRateLawsSettingsReachTheirOwnCommands) {
  EXPECT_GE(call("SetDecisionThreshold", "d", 0.2), 0);
  EXPECT_DOUBLE_EQ(handler_.threshold, 0.2);
  EXPECT_GE(call("SetTargetRate", "d", 150.0), 0);
  EXPECT_DOUBLE_EQ(handler_.rate_l_per_ha, 150.0);
  EXPECT_DOUBLE_EQ(handler_.threshold, 0.2) << "SetTargetRate reached the threshold";
  EXPECT_DOUBLE_EQ(handler_.setpoint, -1) << "a rate law setting reached the set-point";
  EXPECT_LT(call("SetTargetRate", "d", 0.0), 0);
  EXPECT_EQ(error_name(), kErrorInvalidArgument);
  EXPECT_EQ(error_message(), "no dose");
  EXPECT_LT(call("SetDecisionThreshold", "s", "0.3"), 0);
  EXPECT_DOUBLE_EQ(handler_.threshold, 0.2) << "the handler ran on an argument it never got";
}

TEST_F(DbusMethodTest, TheCalibrationMethodsReachTheirCommands) {
  EXPECT_GE(call("StartCatchTest", "d", 30.0), 0);
  EXPECT_DOUBLE_EQ(handler_.catch_test_s, 30.0);
  EXPECT_GE(call("CalibrateMeter", "d", 2.5), 0);
  EXPECT_DOUBLE_EQ(handler_.meter_volume_l, 2.5);
  EXPECT_DOUBLE_EQ(handler_.catch_test_s, 30.0) << "CalibrateMeter started a catch test";
  EXPECT_LT(call("CalibrateNozzles"), 0);
  EXPECT_EQ(handler_.nozzle_calibrations, 1);
  EXPECT_EQ(error_name(), kErrorNotPermitted);
  EXPECT_LT(call("CalibrateMeter"), 0) << "no volume given";
}

TEST_F(DbusMethodTest, TheCommissioningTestsReachTheirCommands) {
  EXPECT_GE(call("TestValve", "udd", 2U, 50.0, 5.0), 0);
  EXPECT_EQ(handler_.tested_valve, (std::array<double, 3>{2.0, 50.0, 5.0}));
  EXPECT_GE(call("TestPump", "d", 20.0), 0);
  EXPECT_DOUBLE_EQ(handler_.pump_test_s, 20.0);
  EXPECT_LT(call("TestValve", "u", 1U), 0) << "no duty and time given";
  EXPECT_EQ(handler_.tested_valve[0], 2.0);
}

TEST_F(DbusMethodTest, ASharedMotionSampleReachesItsCommandWhole) {
  EXPECT_GE(call("FeedSharedMotion", "ddt", 2.5, 104.75, std::uint64_t{9000000000}), 0);
  EXPECT_EQ(handler_.shared_motion, (std::array<double, 3>{2.5, 104.75, 9e9}));
  EXPECT_LT(call("FeedSharedMotion", "dd", 1.0, 2.0), 0) << "no sender time given";
  EXPECT_EQ(handler_.shared_motion[0], 2.5);
  EXPECT_GE(call("Motion"), 0);
  EXPECT_EQ(handler_.shared_fix.mode, io::GnssFixMode::kNone) << "FeedSharedMotion has no fix";
}

TEST_F(DbusMethodTest, ASharedFixReachesItsCommandWhole) {
  EXPECT_GE(
      call("FeedSharedMotionWithFix", "ddtdddutx", 2.5, 104.75, std::uint64_t{9000000000}, 52.25,
           5.5, 270.0, 3U, std::uint64_t{8900000000}, std::int64_t{1782311401000000000}),
      0);
  EXPECT_EQ(handler_.shared_motion, (std::array<double, 3>{2.5, 104.75, 9e9}));
  EXPECT_DOUBLE_EQ(handler_.shared_fix.latitude_deg, 52.25);
  EXPECT_DOUBLE_EQ(handler_.shared_fix.longitude_deg, 5.5);
  EXPECT_DOUBLE_EQ(handler_.shared_fix.heading_deg, 270.0);
  EXPECT_EQ(handler_.shared_fix.mode, io::GnssFixMode::k3D);
  EXPECT_EQ(handler_.shared_fix.sender_time_ns, 8900000000U);
  EXPECT_EQ(handler_.shared_fix.utc_ns, 1782311401000000000);
  EXPECT_GE(call("FeedSharedMotionWithFix", "ddtdddutx", 1.0, 2.0, std::uint64_t{1}, 0.0, 0.0, 0.0,
                 7U, std::uint64_t{1}, std::int64_t{0}),
            0);
  EXPECT_EQ(handler_.shared_fix.mode, io::GnssFixMode::kNone) << "an unknown mode is no fix";
  EXPECT_LT(call("FeedSharedMotionWithFix", "ddt", 1.0, 2.0, std::uint64_t{1}), 0)
      << "no fix given";
  EXPECT_GE(call("MotionWithFix"), 0);
}

TEST_F(DbusMethodTest, ARefusalBecomesTheNamedError) {
  EXPECT_LT(call("SetPressureSetpoint", "d", -1.0), 0);
  EXPECT_EQ(error_name(), kErrorInvalidArgument);
  EXPECT_EQ(error_message(), "not positive");
}

TEST_F(DbusMethodTest, AWrongArgumentTypeIsAnErrorNotACall) {
  EXPECT_LT(call("SetPressureSetpoint", "s", "0.3"), 0);
  EXPECT_DOUBLE_EQ(handler_.setpoint, -1) << "the handler ran on an argument it never got";
  EXPECT_LT(call("SetPressureSetpoint"), 0);
}

TEST_F(DbusMethodTest, AnExceptionInTheHandlerBecomesTheCallersErrorAndGoesNoFurther) {
  handler_.throw_on_start = true;
  EXPECT_LT(call("Start"), 0);
  EXPECT_EQ(handler_.starts, 1);
  EXPECT_EQ(error_name(), SD_BUS_ERROR_FAILED);
  EXPECT_EQ(error_message(), "Start failed: boom");
  EXPECT_LT(call("ReloadConfig"), 0);  // throws an int
  EXPECT_EQ(error_message(), "unknown error");
  // The service goes on answering.
  handler_.throw_on_start = false;
  call("Start");
  EXPECT_EQ(handler_.starts, 2);
}

TEST_F(DbusMethodTest, AnAcceptedSnapshotIsAnsweredLaterByTheHandler) {
  // > 0: handled, and no reply sent now (sd-bus sends none either); the handler keeps one.
  EXPECT_GT(call("Snapshot", "u", 0u), 0);
  EXPECT_EQ(handler_.snapshot_camera, 0);
  ASSERT_TRUE(handler_.snapshot_reply) << "no reply function kept for later";
  EXPECT_EQ(error_name(), "");
  const std::uint8_t png[] = {0x89, 'P', 'N', 'G'};
  handler_.snapshot_reply({}, png);  // the call stays referenced until now
}

TEST_F(DbusMethodTest, ARefusedSnapshotIsTheNamedErrorAtOnce) {
  EXPECT_LT(call("Snapshot", "u", 3u), 0);
  EXPECT_EQ(handler_.snapshot_camera, 3);
  EXPECT_EQ(error_name(), kErrorRateLimited);
  EXPECT_EQ(error_message(), "at most 2 a second");
  EXPECT_LT(call("Snapshot", "s", "0"), 0);  // a camera must be a number
  EXPECT_EQ(handler_.snapshot_camera, 3) << "the handler ran on an argument it never got";
}

TEST_F(DbusMethodTest, AnUnknownMethodIsNamed) {
  EXPECT_LT(call("Explode"), 0);
  EXPECT_EQ(error_name(), SD_BUS_ERROR_UNKNOWN_METHOD);
  EXPECT_EQ(error_message(), "no method Explode");
}

}  // namespace
}  // namespace weedspray::daemon
