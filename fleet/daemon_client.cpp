// SPDX-License-Identifier: Apache-2.0
#include "fleet/daemon_client.hpp"

#include <cstring>
#include <map>
#include <memory>
#include <stdexcept>
#include <string_view>

#include "daemon/bus/dbus_names.hpp"

namespace weedspray::fleet {
namespace {

using daemon::kBusName;
using daemon::kInterface;
using daemon::kObjectPath;

constexpr const char* kPropertiesInterface = "org.freedesktop.DBus.Properties";
constexpr std::uint64_t kCallTimeoutUs = 5'000'000;

std::runtime_error bus_error(const char* what, int r) {
  std::string text = what;
  text += ": ";
  text += std::strerror(-r);
  return std::runtime_error(text);
}

// Reads the variant's value of the given basic type into `out`.
template <class T>
int read_basic(sd_bus_message* m, const char* type, T& out) {
  int r = sd_bus_message_enter_container(m, 'v', type);
  if (r < 0) return r;
  if constexpr (std::is_same_v<T, std::string>) {
    const char* text = nullptr;
    r = sd_bus_message_read_basic(m, type[0], &text);
    if (r >= 0) out = text;
  } else if constexpr (std::is_same_v<T, bool>) {
    int value = 0;
    r = sd_bus_message_read_basic(m, type[0], &value);
    if (r >= 0) out = value != 0;
  } else {
    r = sd_bus_message_read_basic(m, type[0], &out);
  }
  return r < 0 ? r : sd_bus_message_exit_container(m);
}

int read_doubles(sd_bus_message* m, std::vector<double>& out) {
  int r = sd_bus_message_enter_container(m, 'v', "ad");
  const void* data = nullptr;
  std::size_t size = 0;
  if (r >= 0) r = sd_bus_message_read_array(m, 'd', &data, &size);
  if (r < 0) return r;
  const auto* values = static_cast<const double*>(data);
  out.assign(values, values + size / sizeof(double));
  return sd_bus_message_exit_container(m);
}

int read_alarms(sd_bus_message* m, std::vector<AlarmEntry>& out) {
  int r = sd_bus_message_enter_container(m, 'v', "a(ssbs)");
  if (r >= 0) r = sd_bus_message_enter_container(m, 'a', "(ssbs)");
  if (r < 0) return r;
  out.clear();
  const char* name = nullptr;
  const char* severity = nullptr;
  int present = 0;
  const char* remedy = nullptr;
  while ((r = sd_bus_message_read(m, "(ssbs)", &name, &severity, &present, &remedy)) > 0) {
    out.push_back({name, severity, present != 0, remedy});
  }
  if (r < 0) return r;
  r = sd_bus_message_exit_container(m);
  return r < 0 ? r : sd_bus_message_exit_container(m);
}

int read_estop(sd_bus_message* m, BoardSnapshot& s) {
  int closed = 1;
  int latched = 0;
  double reaction_ms = 0;
  int r = sd_bus_message_enter_container(m, 'v', "(bbd)");
  if (r >= 0) r = sd_bus_message_read(m, "(bbd)", &closed, &latched, &reaction_ms);
  if (r < 0) return r;
  s.estop_circuit_closed = closed != 0;
  s.estop_latched = latched != 0;
  return sd_bus_message_exit_container(m);
}

using PropertyReader = int (*)(sd_bus_message*, BoardSnapshot&);
#define WS_READ(expression) +[](sd_bus_message* m, BoardSnapshot& s) { return expression; }

const std::map<std::string_view, PropertyReader>& property_readers() {
  static const std::map<std::string_view, PropertyReader> readers = {
      {"State", WS_READ(read_basic(m, "s", s.state))},
      {"Mode", WS_READ(read_basic(m, "s", s.mode))},
      {"Pressure", WS_READ(read_basic(m, "d", s.pressure_mpa))},
      {"PressureSetpoint", WS_READ(read_basic(m, "d", s.pressure_setpoint_mpa))},
      {"Flow", WS_READ(read_basic(m, "d", s.flow_l_per_min))},
      {"TankLevel", WS_READ(read_basic(m, "d", s.tank_level_pct))},
      {"Speed", WS_READ(read_basic(m, "d", s.speed_m_per_s))},
      {"Distance", WS_READ(read_basic(m, "d", s.distance_m))},
      {"SpeedSource", WS_READ(read_basic(m, "s", s.speed_source))},
      {"GnssFix", WS_READ(read_basic(m, "s", s.gnss_fix))},
      {"NozzleDuty", WS_READ(read_doubles(m, s.nozzle_duty_pct))},
      {"ZoneDensity", WS_READ(read_doubles(m, s.zone_density))},
      {"DecisionThreshold", WS_READ(read_basic(m, "d", s.decision_threshold))},
      {"TargetRate", WS_READ(read_basic(m, "d", s.target_rate_l_per_ha))},
      {"NozzleHealth", WS_READ(read_doubles(m, s.nozzle_health))},
      {"AlarmDetails", WS_READ(read_alarms(m, s.alarms))},
      {"VolumeSprayed", WS_READ(read_basic(m, "d", s.volume_sprayed_l))},
      {"AreaCovered", WS_READ(read_basic(m, "d", s.area_covered_m2))},
      {"SavingsPercent", WS_READ(read_basic(m, "d", s.savings_pct))},
      {"FrameRate", WS_READ(read_basic(m, "d", s.frame_rate_hz))},
      {"VisionLatencyMs", WS_READ(read_basic(m, "d", s.vision_latency_ms))},
      {"VisionLatencyP99Ms", WS_READ(read_basic(m, "d", s.vision_latency_p99_ms))},
      {"ControlOverruns", WS_READ(read_basic(m, "t", s.control_overruns))},
      {"Estop", WS_READ(read_estop(m, s))},
  };
  return readers;
}

// A method error's name and message as one line.
std::string error_text(const sd_bus_error* error) {
  std::string text = error->name != nullptr ? error->name : "error";
  if (error->message != nullptr) text += std::string(": ") + error->message;
  return text;
}

struct PendingCall {
  DaemonClient::Reply reply;
};

int on_method_reply(sd_bus_message* message, void* userdata, sd_bus_error*) {
  std::unique_ptr<PendingCall> pending(static_cast<PendingCall*>(userdata));
  const sd_bus_error* error = sd_bus_message_get_error(message);
  if (error == nullptr) {
    pending->reply(Refusal::kNone, "");
  } else {
    pending->reply(Refusal::kFailed, error_text(error));
  }
  return 0;
}

int on_picture_reply(sd_bus_message* message, void* userdata, sd_bus_error*) {
  std::unique_ptr<DaemonClient::PictureReply> reply(
      static_cast<DaemonClient::PictureReply*>(userdata));
  if (const sd_bus_error* error = sd_bus_message_get_error(message)) {
    (*reply)("", error_text(error));
    return 0;
  }
  const void* data = nullptr;
  std::size_t size = 0;
  const int r = sd_bus_message_read_array(message, 'y', &data, &size);
  if (r < 0) {
    (*reply)("", std::string("malformed Snapshot reply: ") + std::strerror(-r));
  } else {
    (*reply)(std::string(static_cast<const char*>(data), size), "");
  }
  return 0;
}

int on_motion_reply(sd_bus_message* message, void* userdata, sd_bus_error*) {
  std::unique_ptr<DaemonClient::MotionReply> reply(
      static_cast<DaemonClient::MotionReply*>(userdata));
  if (const sd_bus_error* error = sd_bus_message_get_error(message)) {
    (*reply)({}, error_text(error));
    return 0;
  }
  MotionSample sample;
  MotionFix& fix = sample.fix;
  const int r = sd_bus_message_read(message, "ddtdddutx", &sample.speed_m_per_s, &sample.distance_m,
                                    &sample.time_ns, &fix.latitude_deg, &fix.longitude_deg,
                                    &fix.heading_deg, &fix.mode, &fix.time_ns, &fix.utc_ns);
  if (r < 0) {
    (*reply)({}, std::string("malformed MotionWithFix reply: ") + std::strerror(-r));
  } else {
    (*reply)(sample, "");
  }
  return 0;
}

}  // namespace

int read_properties(sd_bus_message* m, BoardSnapshot& snapshot) {
  int r = sd_bus_message_enter_container(m, 'a', "{sv}");
  if (r < 0) return r;
  const auto& readers = property_readers();
  while ((r = sd_bus_message_enter_container(m, 'e', "sv")) > 0) {
    const char* name = nullptr;
    r = sd_bus_message_read(m, "s", &name);
    if (r < 0) return r;
    const auto reader = readers.find(name);
    r = reader != readers.end() ? reader->second(m, snapshot) : sd_bus_message_skip(m, "v");
    if (r < 0) return r;
    r = sd_bus_message_exit_container(m);
    if (r < 0) return r;
  }
  if (r < 0) return r;
  return sd_bus_message_exit_container(m);
}

DaemonClient::DaemonClient(sd_event* event, bool user_bus, DaemonListener& listener)
    : listener_(listener) {
  int r = user_bus ? sd_bus_open_user(&bus_) : sd_bus_open_system(&bus_);
  if (r < 0)
    throw bus_error(user_bus ? "cannot reach the session bus" : "cannot reach the system bus", r);
  // Matched on the path alone (sd-bus cannot match a well-known sender name locally); the
  // sender is then checked against the name's owner, so no other client can pose as it.
  r = sd_bus_match_signal(bus_, &properties_slot_, nullptr, kObjectPath, kPropertiesInterface,
                          "PropertiesChanged", &DaemonClient::on_properties_changed, this);
  if (r >= 0) {
    r = sd_bus_match_signal(bus_, &owner_slot_, "org.freedesktop.DBus", "/org/freedesktop/DBus",
                            "org.freedesktop.DBus", "NameOwnerChanged",
                            &DaemonClient::on_name_owner_changed, this);
  }
  if (r >= 0) {
    r = sd_bus_match_signal(bus_, &disconnected_slot_, nullptr, "/org/freedesktop/DBus/Local",
                            "org.freedesktop.DBus.Local", "Disconnected",
                            &DaemonClient::on_disconnected, this);
  }
  if (r < 0) throw bus_error("cannot watch the daemon's signals", r);
  r = sd_bus_attach_event(bus_, event, SD_EVENT_PRIORITY_NORMAL);
  if (r < 0) throw bus_error("cannot attach the bus to the event loop", r);
  request_all();
}

DaemonClient::~DaemonClient() {
  for (sd_bus_slot* slot : {properties_slot_, owner_slot_, disconnected_slot_}) {
    if (slot != nullptr) sd_bus_slot_unref(slot);
  }
  if (bus_ != nullptr) {
    sd_bus_detach_event(bus_);
    sd_bus_flush_close_unref(bus_);
  }
}

void DaemonClient::request_all() {
  const int r =
      sd_bus_call_method_async(bus_, nullptr, kBusName, kObjectPath, kPropertiesInterface, "GetAll",
                               &DaemonClient::on_get_all, this, "s", kInterface);
  if (r < 0) set_present(false);
}

void DaemonClient::set_present(bool present) {
  if (present == present_) return;
  present_ = present;
  listener_.daemon_present(present);
}

void DaemonClient::take_properties(sd_bus_message* message) {
  if (read_properties(message, snapshot_) < 0) return;
  set_present(true);
  listener_.snapshot_changed();
}

int DaemonClient::on_get_all(sd_bus_message* message, void* userdata, sd_bus_error*) {
  auto* self = static_cast<DaemonClient*>(userdata);
  if (sd_bus_message_is_method_error(message, nullptr)) {
    self->set_present(false);  // not there yet: NameOwnerChanged says when it comes
    return 0;
  }
  const char* sender = sd_bus_message_get_sender(message);
  self->owner_ = sender != nullptr ? sender : "";
  self->take_properties(message);
  return 0;
}

int DaemonClient::on_properties_changed(sd_bus_message* message, void* userdata, sd_bus_error*) {
  auto* self = static_cast<DaemonClient*>(userdata);
  const char* sender = sd_bus_message_get_sender(message);
  if (self->owner_.empty() || sender == nullptr || self->owner_ != sender) return 0;
  const char* interface = nullptr;
  if (sd_bus_message_read(message, "s", &interface) < 0 ||
      std::string_view(interface) != kInterface) {
    return 0;
  }
  self->take_properties(message);
  return 0;
}

int DaemonClient::on_name_owner_changed(sd_bus_message* message, void* userdata, sd_bus_error*) {
  auto* self = static_cast<DaemonClient*>(userdata);
  const char* name = nullptr;
  const char* old_owner = nullptr;
  const char* new_owner = nullptr;
  if (sd_bus_message_read(message, "sss", &name, &old_owner, &new_owner) < 0 ||
      std::string_view(name) != kBusName) {
    return 0;
  }
  self->owner_ = new_owner;
  if (new_owner[0] == '\0') {
    self->set_present(false);
  } else {
    self->request_all();
  }
  return 0;
}

int DaemonClient::on_disconnected(sd_bus_message*, void* userdata, sd_bus_error*) {
  static_cast<DaemonClient*>(userdata)->listener_.bus_lost();
  return 0;
}

void DaemonClient::call(const MethodCall& call, Reply reply) {
  sd_bus_message* message = nullptr;
  int r = sd_bus_message_new_method_call(bus_, &message, kBusName, kObjectPath, kInterface,
                                         call.method.c_str());
  if (r >= 0 && call.argument) r = sd_bus_message_append(message, "d", *call.argument);
  auto pending = std::make_unique<PendingCall>(PendingCall{std::move(reply)});
  if (r >= 0) {
    r = sd_bus_call_async(bus_, nullptr, message, on_method_reply, pending.get(), kCallTimeoutUs);
  }
  sd_bus_message_unref(message);
  if (r < 0) {
    std::string text = "cannot call ";
    text += call.method;
    text += ": ";
    text += std::strerror(-r);
    pending->reply(Refusal::kFailed, text);
    return;
  }
  (void)pending.release();  // on_method_reply owns it now
}

void DaemonClient::picture(std::uint32_t camera, PictureReply reply) {
  auto pending = std::make_unique<PictureReply>(std::move(reply));
  const int r = sd_bus_call_method_async(bus_, nullptr, kBusName, kObjectPath, kInterface,
                                         "Snapshot", on_picture_reply, pending.get(), "u", camera);
  if (r < 0) {
    (*pending)("", std::string("cannot call Snapshot: ") + std::strerror(-r));
    return;
  }
  (void)pending.release();  // on_picture_reply owns it now
}

}  // namespace weedspray::fleet

namespace weedspray::fleet {

void DaemonClient::motion(MotionReply reply) {
  auto pending = std::make_unique<MotionReply>(std::move(reply));
  const int r = sd_bus_call_method_async(bus_, nullptr, kBusName, kObjectPath, kInterface,
                                         "MotionWithFix", on_motion_reply, pending.get(), "");
  if (r < 0) {
    (*pending)({}, std::string("cannot call MotionWithFix: ") + std::strerror(-r));
    return;
  }
  (void)pending.release();  // on_motion_reply owns it now
}

void DaemonClient::feed_motion(const MotionSample& sample, Reply reply) {
  auto pending = std::make_unique<PendingCall>(PendingCall{std::move(reply)});
  const int r = sd_bus_call_method_async(
      bus_, nullptr, kBusName, kObjectPath, kInterface, "FeedSharedMotionWithFix", on_method_reply,
      pending.get(), "ddtdddutx", sample.speed_m_per_s, sample.distance_m, sample.time_ns,
      sample.fix.latitude_deg, sample.fix.longitude_deg, sample.fix.heading_deg, sample.fix.mode,
      sample.fix.time_ns, sample.fix.utc_ns);
  if (r < 0) {
    pending->reply(Refusal::kFailed,
                   std::string("cannot call FeedSharedMotionWithFix: ") + std::strerror(-r));
    return;
  }
  (void)pending.release();  // on_method_reply owns it now
}

}  // namespace weedspray::fleet
