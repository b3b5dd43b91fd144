// SPDX-License-Identifier: Apache-2.0
#include "fleet/broker_settings.hpp"

namespace weedspray::fleet {

MqttSettings broker_settings(const daemon::FleetSection& f, std::string client_id,
                             std::string will_topic, std::vector<std::string> subscriptions) {
  MqttSettings s;
  s.host = f.host;
  s.port = f.port;
  s.keepalive_s = f.keepalive_s;
  s.client_id = std::move(client_id);
  s.username = f.username;
  if (!f.password_file.empty()) s.password = read_password_file(f.password_file);
  s.tls_cafile = f.tls_cafile;
  s.tls_certfile = f.tls_certfile;
  s.tls_keyfile = f.tls_keyfile;
  s.will_topic = std::move(will_topic);
  s.subscriptions = std::move(subscriptions);
  return s;
}

}  // namespace weedspray::fleet
