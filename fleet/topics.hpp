// SPDX-License-Identifier: Apache-2.0
// The MQTT topics of one board of a machine (docs/fleet.md): weedspray/<machine>/<board>/...
// for what it publishes, weedspray/<machine>/cmd and weedspray/<machine>/<board>/cmd for the
// commands it takes.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace weedspray::fleet {

class Topics {
 public:
  Topics(const std::string& machine, const std::string& board)
      : machine_("weedspray/" + machine), board_(machine_ + "/" + board) {}

  // weedspray/<machine>/<board>/<leaf>: state, alarms, nozzles, online, reply ...
  [[nodiscard]] std::string board(const std::string& leaf) const { return board_ + "/" + leaf; }
  // weedspray/<machine>/<other board>/<leaf>: what another board of the machine publishes.
  [[nodiscard]] std::string other_board(const std::string& other, const std::string& leaf) const {
    return machine_ + "/" + other + "/" + leaf;
  }
  [[nodiscard]] std::string machine_commands() const { return machine_ + "/cmd"; }
  [[nodiscard]] std::string board_commands() const { return board_ + "/cmd"; }
  // weedspray/<machine>/+/online: every board's online flag.
  [[nodiscard]] std::string every_online() const { return machine_ + "/+/online"; }
  // The board whose online flag `topic` is, if it is one of this machine's.
  [[nodiscard]] std::optional<std::string> online_board(std::string_view topic) const {
    const std::string_view suffix = "/online";
    if (topic.size() <= machine_.size() + 1 + suffix.size() ||
        topic.substr(0, machine_.size() + 1) != machine_ + "/" ||
        topic.substr(topic.size() - suffix.size()) != suffix) {
      return std::nullopt;
    }
    topic.remove_prefix(machine_.size() + 1);
    topic.remove_suffix(suffix.size());
    if (topic.find('/') != std::string_view::npos) return std::nullopt;
    return std::string(topic);
  }

 private:
  std::string machine_;
  std::string board_;
};

}  // namespace weedspray::fleet
