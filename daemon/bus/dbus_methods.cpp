// SPDX-License-Identifier: Apache-2.0
// The org.weedspray.Sprayer1 methods' calls: each read from its message and handed to the
// CommandHandler, its result the reply (now, or later for ReloadConfig and Snapshot).
#include <systemd/sd-bus.h>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "daemon/bus/dbus_service.hpp"

namespace weedspray::daemon {

namespace {

// A deferred call's refusal as its named error reply.
void reply_error_later(sd_bus_message* call, const CommandResult& result) {
  sd_bus_error error = SD_BUS_ERROR_NULL;
  sd_bus_error_set(&error, result.error_name.c_str(), result.message.c_str());
  sd_bus_reply_method_error(call, &error);
  sd_bus_error_free(&error);
}

// The reply to a Snapshot call, sent later: the call is kept referenced until then.
SnapshotReply deferred_snapshot_reply(sd_bus_message* call) {
  std::shared_ptr<sd_bus_message> kept(sd_bus_message_ref(call), sd_bus_message_unref);
  return [kept](const CommandResult& result, std::span<const std::uint8_t> png) {
    if (!result.ok()) {
      reply_error_later(kept.get(), result);
      return;
    }
    sd_bus_message* reply = nullptr;
    if (sd_bus_message_new_method_return(kept.get(), &reply) < 0) return;
    if (sd_bus_message_append_array(reply, 'y', png.data(), png.size()) >= 0)
      sd_bus_send(nullptr, reply, nullptr);
    sd_bus_message_unref(reply);
  };
}

// The reply to a ReloadConfig call, sent later: the call is kept referenced until then.
ReloadReply deferred_reload_reply(sd_bus_message* call) {
  std::shared_ptr<sd_bus_message> kept(sd_bus_message_ref(call), sd_bus_message_unref);
  return [kept](const CommandResult& result) {
    if (result.ok()) {
      sd_bus_reply_method_return(kept.get(), "");
      return;
    }
    reply_error_later(kept.get(), result);
  };
}

int dispatch(sd_bus_message* message, CommandHandler& handler, sd_bus_error* error) {
  const char* member_name = sd_bus_message_get_member(message);
  const std::string_view member(member_name != nullptr ? member_name : "");
  CommandResult result;
  if (member == "Start") {
    result = handler.start();
  } else if (member == "Stop") {
    result = handler.stop();
  } else if (member == "SetPressureSetpoint" || member == "SetDecisionThreshold" ||
             member == "SetTargetRate") {
    double value = 0;
    const int r = sd_bus_message_read(message, "d", &value);
    if (r < 0) return r;
    result = member == "SetPressureSetpoint"    ? handler.set_pressure_setpoint(value)
             : member == "SetDecisionThreshold" ? handler.set_decision_threshold(value)
                                                : handler.set_target_rate(value);
  } else if (member == "ReloadConfig") {
    result = handler.reload_config(deferred_reload_reply(message));
    if (result.ok()) return 1;  // the handler replies once the reload is applied or refused
  } else if (member == "ClearAlarms") {
    result = handler.clear_alarms();
  } else if (member == "InjectSimFault") {
    const char* name = nullptr;
    const int r = sd_bus_message_read(message, "s", &name);
    if (r < 0) return r;
    result = handler.inject_sim_fault(name);
  } else if (member == "Snapshot") {
    std::uint32_t camera = 0;
    const int r = sd_bus_message_read(message, "u", &camera);
    if (r < 0) return r;
    result = handler.snapshot(camera, deferred_snapshot_reply(message));
    if (result.ok()) return 1;  // the handler replies once the frame is there
  } else if (member == "CalibrateWheel") {
    double distance_m = 0;
    const int r = sd_bus_message_read(message, "d", &distance_m);
    if (r < 0) return r;
    std::uint64_t request = 0;
    result = handler.calibrate_wheel(distance_m, request);
    if (result.ok()) return sd_bus_reply_method_return(message, "t", request);
  } else if (member == "StartCatchTest" || member == "CalibrateMeter") {
    double value = 0;
    const int r = sd_bus_message_read(message, "d", &value);
    if (r < 0) return r;
    result = member == "StartCatchTest" ? handler.start_catch_test(value)
                                        : handler.calibrate_meter(value);
  } else if (member == "CalibrateNozzles") {
    result = handler.calibrate_nozzles();
  } else if (member == "TestValve") {
    std::uint32_t nozzle = 0;
    double duty_pct = 0;
    double seconds = 0;
    const int r = sd_bus_message_read(message, "udd", &nozzle, &duty_pct, &seconds);
    if (r < 0) return r;
    result = handler.test_valve(nozzle, duty_pct, seconds);
  } else if (member == "TestPump") {
    double seconds = 0;
    const int r = sd_bus_message_read(message, "d", &seconds);
    if (r < 0) return r;
    result = handler.test_pump(seconds);
  } else if (member == "Motion" || member == "MotionWithFix") {
    double speed_m_per_s = 0;
    double distance_m = 0;
    std::uint64_t time_ns = 0;
    SharedFix fix;
    result = handler.motion(speed_m_per_s, distance_m, time_ns, fix);
    if (result.ok() && member == "Motion")
      return sd_bus_reply_method_return(message, "ddt", speed_m_per_s, distance_m, time_ns);
    if (result.ok()) {
      return sd_bus_reply_method_return(message, "ddtdddutx", speed_m_per_s, distance_m, time_ns,
                                        fix.latitude_deg, fix.longitude_deg, fix.heading_deg,
                                        fix_mode_number(fix.mode), fix.sender_time_ns, fix.utc_ns);
    }
  } else if (member == "FeedSharedMotion" || member == "FeedSharedMotionWithFix") {
    double speed_m_per_s = 0;
    double distance_m = 0;
    std::uint64_t sender_time_ns = 0;
    SharedFix fix;
    int r = sd_bus_message_read(message, "ddt", &speed_m_per_s, &distance_m, &sender_time_ns);
    if (r < 0) return r;
    if (member == "FeedSharedMotionWithFix") {
      std::uint32_t mode = 0;
      r = sd_bus_message_read(message, "dddutx", &fix.latitude_deg, &fix.longitude_deg,
                              &fix.heading_deg, &mode, &fix.sender_time_ns, &fix.utc_ns);
      if (r < 0) return r;
      fix.mode = fix_mode_from_number(mode);
    }
    result = handler.feed_shared_motion(speed_m_per_s, distance_m, sender_time_ns, fix);
  } else {
    return sd_bus_error_setf(error, SD_BUS_ERROR_UNKNOWN_METHOD, "no method %s",
                             std::string(member).c_str());
  }
  if (!result.ok()) {
    return sd_bus_error_set(error, result.error_name.c_str(), result.message.c_str());
  }
  return sd_bus_reply_method_return(message, "");
}

}  // namespace

int handle_method_call(sd_bus_message* message, CommandHandler& handler, sd_bus_error* error) {
  // An exception must not cross sd-bus's C frames: it becomes the caller's error reply.
  try {
    return dispatch(message, handler, error);
  } catch (const std::exception& e) {
    const char* member = sd_bus_message_get_member(message);
    return sd_bus_error_setf(error, SD_BUS_ERROR_FAILED, "%s failed: %s",
                             member != nullptr ? member : "call", e.what());
  } catch (...) {
    return sd_bus_error_set(error, SD_BUS_ERROR_FAILED, "unknown error");
  }
}

}  // namespace weedspray::daemon
