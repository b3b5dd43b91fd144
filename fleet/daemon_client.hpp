// SPDX-License-Identifier: Apache-2.0
// The bridge's side of weedsprayd's D-Bus service (daemon/bus/dbus_names.hpp): follows the
// properties (GetAll, then PropertiesChanged), notices the daemon coming and going
// (NameOwnerChanged), and calls its methods. On the main thread's sd-event loop.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include <systemd/sd-bus.h>
#include <systemd/sd-event.h>

#include "fleet/board_snapshot.hpp"
#include "fleet/fleet_commands.hpp"
#include "fleet/motion.hpp"

namespace weedspray::fleet {

class DaemonListener {
 public:
  virtual ~DaemonListener() = default;
  virtual void snapshot_changed() = 0;
  // The daemon owns its bus name (true) or no longer does (false).
  virtual void daemon_present(bool present) = 0;
  // The bridge's own bus connection closed.
  virtual void bus_lost() = 0;
};

class DaemonClient {
 public:
  // Throws std::runtime_error when the bus cannot be reached.
  DaemonClient(sd_event* event, bool user_bus, DaemonListener& listener);
  ~DaemonClient();
  DaemonClient(const DaemonClient&) = delete;
  DaemonClient& operator=(const DaemonClient&) = delete;

  [[nodiscard]] const BoardSnapshot& snapshot() const { return snapshot_; }
  [[nodiscard]] bool present() const { return present_; }

  // kNone and "" when done, else kFailed and the daemon's (or the bus's) error.
  using Reply = std::function<void(Refusal, const std::string& message)>;
  // Calls the method; `reply` is called once, later, on the event loop.
  void call(const MethodCall& call, Reply reply);
  // The PNG bytes, or "" and the daemon's (or the bus's) error name and message.
  using PictureReply = std::function<void(std::string png, const std::string& error)>;
  // Calls Snapshot(camera); `reply` is called once, later, on the event loop.
  void picture(std::uint32_t camera, PictureReply reply);
  // The sample, or an empty one and the daemon's (or the bus's) error.
  using MotionReply = std::function<void(const MotionSample&, const std::string& error)>;
  // Calls MotionWithFix(); `reply` is called once, later, on the event loop.
  void motion(MotionReply reply);
  // Calls FeedSharedMotionWithFix(speed, distance, time, the fix); `reply` as for call().
  void feed_motion(const MotionSample& sample, Reply reply);

 private:
  static int on_properties_changed(sd_bus_message* message, void* userdata, sd_bus_error*);
  static int on_get_all(sd_bus_message* message, void* userdata, sd_bus_error*);
  static int on_name_owner_changed(sd_bus_message* message, void* userdata, sd_bus_error*);
  static int on_disconnected(sd_bus_message* message, void* userdata, sd_bus_error*);
  void request_all();
  // A properties array read into the snapshot: the daemon is there, and the listener told.
  void take_properties(sd_bus_message* message);
  void set_present(bool present);

  sd_bus* bus_ = nullptr;
  sd_bus_slot* properties_slot_ = nullptr;
  sd_bus_slot* owner_slot_ = nullptr;
  sd_bus_slot* disconnected_slot_ = nullptr;
  DaemonListener& listener_;
  BoardSnapshot snapshot_;
  std::string owner_;  // the daemon's unique bus name ("" while it is away)
  bool present_ = false;
};

// Reads a properties array a{sv} of org.weedspray.Sprayer1 into `snapshot`, skipping those it
// does not follow. Returns a negative errno on a malformed message.
int read_properties(sd_bus_message* message, BoardSnapshot& snapshot);

}  // namespace weedspray::fleet
