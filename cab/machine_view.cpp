// SPDX-License-Identifier: Apache-2.0
#include "cab/machine_view.hpp"

#include <array>

namespace weedspray::cab {
namespace {

// The leaves the page shows (docs/fleet.md); "online" is a bare true/false.
constexpr std::array<std::string_view, 10> kLeaves = {
    "online", "info", "state", "alarms", "nozzles", "pressure", "flow", "speed", "tank", "health"};

}  // namespace

MachineView::MachineView(std::string machine)
    : machine_(std::move(machine)), prefix_("weedspray/" + machine_ + "/") {}

void MachineView::apply(std::string_view topic, std::string_view payload) {
  if (topic.substr(0, prefix_.size()) != prefix_) return;
  topic.remove_prefix(prefix_.size());
  const auto slash = topic.find('/');
  if (slash == std::string_view::npos) return;  // weedspray/<machine>/cmd
  const std::string board(topic.substr(0, slash));
  const std::string_view leaf = topic.substr(slash + 1);
  bool shown = false;
  for (auto known : kLeaves) shown = shown || known == leaf;
  if (!shown) return;
  auto value = nlohmann::json::parse(payload, nullptr, false);
  if (value.is_discarded()) return;
  std::lock_guard lock(mutex_);
  boards_[board][std::string(leaf)] = std::move(value);
}

void MachineView::set_broker_connected(bool connected) {
  std::lock_guard lock(mutex_);
  broker_connected_ = connected;
}

nlohmann::json MachineView::to_json() const {
  std::lock_guard lock(mutex_);
  return {{"machine", machine_}, {"broker_connected", broker_connected_}, {"boards", boards_}};
}

}  // namespace weedspray::cab
