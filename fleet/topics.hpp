// The MQTT topics of one board of a machine (docs/fleet.md): weedspray/<machine>/<board>/...
// for what it publishes, weedspray/<machine>/cmd and weedspray/<machine>/<board>/cmd for the
// commands it takes.
#pragma once

#include <string>

namespace weedspray::fleet {

class Topics {
 public:
  Topics(const std::string& machine, const std::string& board)
      : machine_("weedspray/" + machine), board_(machine_ + "/" + board) {}

  // weedspray/<machine>/<board>/<leaf>: state, alarms, nozzles, online, reply ...
  [[nodiscard]] std::string board(const std::string& leaf) const { return board_ + "/" + leaf; }
  [[nodiscard]] std::string machine_commands() const { return machine_ + "/cmd"; }
  [[nodiscard]] std::string board_commands() const { return board_ + "/cmd"; }

 private:
  std::string machine_;
  std::string board_;
};

}  // namespace weedspray::fleet
