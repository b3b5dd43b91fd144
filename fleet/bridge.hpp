// SPDX-License-Identifier: Apache-2.0
// The fleet bridge proper: publishes the board's snapshot on its topics when it changes, marks
// the board online or lost, and carries the broker's commands to the daemon, replying and
// counting each. Main thread only.
#pragma once

#include <map>
#include <string>

#include "fleet/board_snapshot.hpp"
#include "fleet/daemon_client.hpp"
#include "fleet/fleet_commands.hpp"
#include "fleet/mqtt_link.hpp"
#include "fleet/shared_motion_feed.hpp"
#include "fleet/topics.hpp"

namespace weedspray::fleet {

// What the board does when the machine falls apart (fleet.on_board_lost, on_broker_lost).
struct LossPolicy {
  bool stop_on_board_lost = false;  // another board's online turned false
  bool stop_on_broker_lost = true;  // this board's broker connection closed
};

class Bridge : public DaemonListener {
 public:
  Bridge(MqttLink& mqtt, BoardInfo info, LossPolicy policy);
  // The daemon's side; set once both exist (the client calls back into the bridge).
  void attach(DaemonClient& daemon) { daemon_ = &daemon; }
  // fleet.speed_from's motion topic, handed to the daemon (set once, after attach).
  void take_shared_motion(SharedMotionFeed& feed) { shared_motion_ = &feed; }

  // Everything the MQTT thread queued.
  void on_mqtt_events();
  // Before exiting: online = false, and the link closed with its will.
  void goodbye();
  // The bridge's own bus connection closed: the loop should end (set by bus_lost).
  [[nodiscard]] bool bus_closed() const { return bus_closed_; }

  void snapshot_changed() override;
  void daemon_present(bool present) override;
  void bus_lost() override;

 private:
  void publish_snapshot(bool every_topic);
  void publish_online();
  void handle_command(const MqttEvent& event);
  void finish(const ParsedCommand& command, Refusal refusal, const std::string& message);
  // Another board's online flag; `retained`: a value from before this connection.
  void board_online(const std::string& board, const std::string& payload, bool retained);
  // Stops the daemon on the bridge's own account (the loss policy), saying why.
  void stop_board(const std::string& why);

  MqttLink& mqtt_;
  DaemonClient* daemon_ = nullptr;
  SharedMotionFeed* shared_motion_ = nullptr;
  BoardInfo info_;
  LossPolicy policy_;
  Topics topics_;
  std::map<std::string, std::string> published_;  // leaf -> payload without its time stamp
  CommandCounters counters_;
  bool bus_closed_ = false;
};

}  // namespace weedspray::fleet
