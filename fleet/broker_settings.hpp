// SPDX-License-Identifier: Apache-2.0
// The broker connection of [fleet] (host, port, keep-alive, credentials, TLS) as the MQTT
// link's settings, shared by the bridge and the cab page.
#pragma once

#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "fleet/mqtt_link.hpp"

namespace weedspray::fleet {

// Reads fleet.password_file (throws std::runtime_error naming it when it cannot).
[[nodiscard]] MqttSettings broker_settings(const daemon::FleetSection& fleet, std::string client_id,
                                           std::string will_topic,
                                           std::vector<std::string> subscriptions);

}  // namespace weedspray::fleet
