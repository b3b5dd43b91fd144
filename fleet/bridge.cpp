// SPDX-License-Identifier: Apache-2.0
#include "fleet/bridge.hpp"

#include <chrono>
#include <cstdio>

namespace weedspray::fleet {
namespace {

// Seconds since the Unix epoch, to the millisecond: when the bridge published the value.
double unix_time_s() {
  using namespace std::chrono;
  return static_cast<double>(
             duration_cast<milliseconds>(system_clock::now().time_since_epoch()).count()) /
         1000.0;
}

}  // namespace

Bridge::Bridge(MqttLink& mqtt, BoardInfo info, LossPolicy policy)
    : mqtt_(mqtt), info_(std::move(info)), policy_(policy), topics_(info_.machine, info_.board) {}

void Bridge::publish_snapshot(bool every_topic) {
  if (daemon_ == nullptr || !daemon_->present()) return;
  for (auto& [leaf, payload] : board_payloads(daemon_->snapshot(), info_)) {
    std::string text = payload.dump();
    auto& last = published_[leaf];
    if (!every_topic && last == text) continue;
    last = std::move(text);
    payload["t"] = unix_time_s();
    mqtt_.publish(topics_.board(leaf), payload.dump(), true);
  }
}

void Bridge::publish_online() {
  const bool online = daemon_ != nullptr && daemon_->present();
  mqtt_.publish(topics_.board("online"), online ? "true" : "false", true);
}

void Bridge::snapshot_changed() {
  publish_snapshot(false);
}

void Bridge::daemon_present(bool present) {
  std::fprintf(stderr, "weedsprayd %s\n", present ? "is on the bus" : "left the bus: board lost");
  publish_online();
  if (present) publish_snapshot(true);
}

void Bridge::bus_lost() {
  std::fprintf(stderr, "the D-Bus connection closed\n");
  bus_closed_ = true;
}

void Bridge::goodbye() {
  mqtt_.publish(topics_.board("online"), "false", true);
  mqtt_.disconnect_with_will();
}

void Bridge::on_mqtt_events() {
  for (const auto& event : mqtt_.take()) {
    switch (event.kind) {
      case MqttEvent::Kind::kConnected:
        std::fprintf(stderr, "connected to the broker\n");
        publish_online();
        publish_snapshot(true);
        mqtt_.publish(topics_.board("commands"), counters_.to_json().dump(), true);
        break;
      case MqttEvent::Kind::kDisconnected:
        // A board that takes its speed from another stops receiving it here: its daemon's
        // timeout closes the valves.
        std::fprintf(stderr, "the broker connection closed; reconnecting\n");
        if (policy_.stop_on_broker_lost) stop_board("the broker connection was lost");
        break;
      case MqttEvent::Kind::kMessage:
        if (const auto board = topics_.online_board(event.topic)) {
          board_online(*board, event.payload, event.retained);
        } else if (shared_motion_ != nullptr && shared_motion_->take(event)) {
          // handed to the daemon (or dropped, and counted)
        } else {
          handle_command(event);
        }
        break;
    }
  }
}

void Bridge::board_online(const std::string& board, const std::string& payload, bool retained) {
  // A board already lost before this connection is no news: only a loss seen live stops.
  if (board == info_.board || retained || payload != "false") return;
  std::fprintf(stderr, "board %s of the machine is lost\n", board.c_str());
  if (policy_.stop_on_board_lost) stop_board("board " + board + " was lost");
}

void Bridge::stop_board(const std::string& why) {
  if (daemon_ == nullptr || !daemon_->present() || daemon_->snapshot().state != "Spraying") return;
  std::fprintf(stderr, "stopping: %s\n", why.c_str());
  daemon_->call({"Stop", std::nullopt}, [this, why](Refusal refusal, const std::string& message) {
    std::fprintf(stderr, "stop (%s): %s\n", why.c_str(),
                 refusal == Refusal::kNone ? "done" : message.c_str());
    const nlohmann::json event{{"command", "stop"},
                               {"id", nullptr},
                               {"ok", refusal == Refusal::kNone},
                               {"reason", refusal_name(refusal)},
                               {"message", "stopped by the bridge: " + why}};
    mqtt_.publish(topics_.board("reply"), event.dump(), false);
  });
}

void Bridge::handle_command(const MqttEvent& event) {
  ParsedCommand command = parse_command(event.payload, info_.commands);
  if (command.refusal == Refusal::kNone && event.retained) {
    // A retained command would be carried out again on every connection of every board.
    command.refusal = Refusal::kMalformed;
    command.message = "retained: commands must not be retained";
  }
  if (command.refusal != Refusal::kNone) {
    finish(command, command.refusal, command.message);
    return;
  }
  if (daemon_ == nullptr || !daemon_->present()) {
    finish(command, Refusal::kFailed, "weedsprayd is not on the bus");
    return;
  }
  daemon_->call(command.call, [this, command](Refusal refusal, const std::string& message) {
    finish(command, refusal, message);
  });
}

void Bridge::finish(const ParsedCommand& command, Refusal refusal, const std::string& message) {
  counters_.count(refusal);
  if (refusal != Refusal::kNone) {
    std::fprintf(stderr, "command \"%s\" refused (%s): %s\n", command.kind.c_str(),
                 std::string(refusal_name(refusal)).c_str(), message.c_str());
  }
  mqtt_.publish(topics_.board("reply"), command_reply(command, refusal, message).dump(), false);
  mqtt_.publish(topics_.board("commands"), counters_.to_json().dump(), true);
}

}  // namespace weedspray::fleet
