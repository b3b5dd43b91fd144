// SPDX-License-Identifier: Apache-2.0
// What the cab knows of its machine: the latest payload of every board's topic under
// weedspray/<machine>/, folded from the broker's messages into one JSON document for the page.
// Thread-safe: the MQTT side writes, the HTTP side reads.
#pragma once

#include <mutex>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace weedspray::cab {

class MachineView {
 public:
  explicit MachineView(std::string machine);

  // A message on weedspray/<machine>/<board>/<leaf>; other topics, command and reply topics
  // and payloads that are not JSON are ignored.
  void apply(std::string_view topic, std::string_view payload);
  void set_broker_connected(bool connected);

  // {"machine", "broker_connected", "boards": {"<board>": {"online", "<leaf>": {...}}}}
  [[nodiscard]] nlohmann::json to_json() const;

 private:
  std::string machine_;
  std::string prefix_;  // "weedspray/<machine>/"
  mutable std::mutex mutex_;
  nlohmann::json boards_ = nlohmann::json::object();
  bool broker_connected_ = false;
};

}  // namespace weedspray::cab
