// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayctl/bus_client.hpp"

#include <cerrno>
#include <csignal>
#include <cstring>

#include "daemon/bus/dbus_names.hpp"

namespace weedspray::sprayctl {

using daemon::kBusName;
using daemon::kInterface;
using daemon::kObjectPath;

namespace {

// sd-bus's errors for a bus that cannot be reached: no address (no session bus: ENOMEDIUM),
// no socket, refused or dropped connection.
bool is_connection_error(int r) {
  for (const int e : {ENOMEDIUM, ENOENT, ECONNREFUSED, ECONNRESET, ENOTCONN, EPIPE, ENXIO})
    if (r == -e) return true;
  return false;
}

// Owns a reply message.
struct Reply {
  sd_bus_message* m = nullptr;
  ~Reply() { sd_bus_message_unref(m); }
};

}  // namespace

BusClient::BusClient(bool user_bus) : bus_kind_(user_bus ? "session" : "system") {
  const int r = user_bus ? sd_bus_open_user(&bus_) : sd_bus_open_system(&bus_);
  if (r < 0) throw unreachable_bus(r);
}

BusClient::~BusClient() {
  sd_bus_flush_close_unref(bus_);
}

Properties BusClient::get_all() {
  sd_bus_error error = SD_BUS_ERROR_NULL;
  Reply reply;
  const int r = sd_bus_call_method(bus_, kBusName, kObjectPath, "org.freedesktop.DBus.Properties",
                                   "GetAll", &error, &reply.m, "s", kInterface);
  if (r < 0) fail(error, r);
  return read_properties(reply.m);
}

Value BusClient::get(const char* property) {
  sd_bus_error error = SD_BUS_ERROR_NULL;
  Reply reply;
  const int r = sd_bus_call_method(bus_, kBusName, kObjectPath, "org.freedesktop.DBus.Properties",
                                   "Get", &error, &reply.m, "ss", kInterface, property);
  if (r < 0) fail(error, r);
  return read_variant(reply.m);
}

void BusClient::call(const char* method, const char* signature, double argument) {
  sd_bus_error error = SD_BUS_ERROR_NULL;
  Reply reply;
  const std::string_view sig(signature);
  const int r = sig.empty() ? sd_bus_call_method(bus_, kBusName, kObjectPath, kInterface, method,
                                                 &error, &reply.m, "")
                : sig == "u"
                    ? sd_bus_call_method(bus_, kBusName, kObjectPath, kInterface, method, &error,
                                         &reply.m, "u", static_cast<std::uint32_t>(argument))
                    : sd_bus_call_method(bus_, kBusName, kObjectPath, kInterface, method, &error,
                                         &reply.m, "d", argument);
  if (r < 0) fail(error, r);
}

void BusClient::test_valve(std::uint32_t nozzle, double duty_pct, double seconds) {
  sd_bus_error error = SD_BUS_ERROR_NULL;
  Reply reply;
  const int r = sd_bus_call_method(bus_, kBusName, kObjectPath, kInterface, "TestValve", &error,
                                   &reply.m, "udd", nozzle, duty_pct, seconds);
  if (r < 0) fail(error, r);
}

std::uint64_t BusClient::calibrate_wheel(double run_distance_m) {
  sd_bus_error error = SD_BUS_ERROR_NULL;
  Reply reply;
  const int r = sd_bus_call_method(bus_, kBusName, kObjectPath, kInterface, "CalibrateWheel",
                                   &error, &reply.m, "d", run_distance_m);
  if (r < 0) fail(error, r);
  std::uint64_t request = 0;
  check(sd_bus_message_read(reply.m, "t", &request), "read the request");
  return request;
}

std::vector<std::uint8_t> BusClient::snapshot(std::uint32_t camera) {
  sd_bus_error error = SD_BUS_ERROR_NULL;
  Reply reply;
  const int r = sd_bus_call_method(bus_, kBusName, kObjectPath, kInterface, "Snapshot", &error,
                                   &reply.m, "u", camera);
  if (r < 0) fail(error, r);
  const void* data = nullptr;
  std::size_t size = 0;
  check(sd_bus_message_read_array(reply.m, 'y', &data, &size), "read the PNG");
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  return {bytes, bytes + size};
}

int BusClient::follow_signals(const EventHandler& handler) {
  const std::string match =
      std::string("type='signal',sender='") + kBusName + "',path='" + kObjectPath + "'";
  handler_ = &handler;
  check(sd_bus_add_match(bus_, nullptr, match.c_str(), &BusClient::on_signal, this), "add match");
  static volatile std::sig_atomic_t stop = 0;
  std::signal(SIGINT, [](int) { stop = 1; });
  std::signal(SIGTERM, [](int) { stop = 1; });
  while (!stop) {
    const int r = sd_bus_process(bus_, nullptr);
    if (r < 0 && r != -EINTR) check(r, "process");
    if (r > 0) continue;
    const int w = sd_bus_wait(bus_, 500000);
    if (w < 0 && w != -EINTR) check(w, "wait");
  }
  return 0;
}

int BusClient::on_signal(sd_bus_message* m, void* userdata, sd_bus_error*) {
  const auto& self = *static_cast<BusClient*>(userdata);
  const std::string member = sd_bus_message_get_member(m);
  if (member == "PropertiesChanged") {
    const char* interface = nullptr;
    if (sd_bus_message_read(m, "s", &interface) < 0) return 0;
    for (const auto& [name, value] : read_properties(m)) (*self.handler_)("property", name, value);
  } else if (member == "AlarmRaised" || member == "AlarmCleared") {
    const char* name = nullptr;
    if (sd_bus_message_read(m, "s", &name) < 0) return 0;
    (*self.handler_)(member == "AlarmRaised" ? "alarm-raised" : "alarm-cleared", name, name);
  }
  return 0;
}

// A failed call: the daemon's own refusal keeps its error name and message; the bus saying
// that nobody owns the name, or a connection that cannot be made, is "not reachable".
void BusClient::fail(sd_bus_error& error, int r) const {
  const std::string name = error.name ? error.name : "";
  std::string message = error.message ? error.message : std::strerror(-r);
  sd_bus_error_free(&error);
  if (name == SD_BUS_ERROR_SERVICE_UNKNOWN || name == SD_BUS_ERROR_NAME_HAS_NO_OWNER) {
    throw BusError{
        std::string("weedsprayd is not running (no ") + kBusName + " on the " + bus_kind_ + " bus)",
        kExitUnreachable};
  }
  if (name == SD_BUS_ERROR_NO_REPLY || name == SD_BUS_ERROR_TIMEOUT || r == -ETIMEDOUT)
    throw BusError{"weedsprayd did not answer: " + message, kExitUnreachable};
  if (name.empty() && is_connection_error(r)) throw unreachable_bus(r);
  if (!name.empty()) message = name + ": " + message;
  throw BusError{message};
}

BusError BusClient::unreachable_bus(int r) const {
  if (r == -ENOMEDIUM) {
    return BusError{"weedsprayd is not reachable: this shell has no " + bus_kind_ +
                        " bus (set DBUS_SESSION_BUS_ADDRESS to the bus weedsprayd --user is on)",
                    kExitUnreachable};
  }
  return BusError{"weedsprayd is not running (cannot connect to the " + bus_kind_ +
                      " bus: " + std::strerror(-r) + ")",
                  kExitUnreachable};
}

}  // namespace weedspray::sprayctl
