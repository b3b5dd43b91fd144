// SPDX-License-Identifier: Apache-2.0
// The bridge's connection to the MQTT broker (libmosquitto, MQTT 5): its own network thread
// (mosquitto_loop_start) reconnects by itself; what arrives (a connection made, a message) is
// queued and an eventfd wakes the main thread's sd-event loop, which takes it with take().
// A last will marks the board lost: <online> = false, retained.
#pragma once

#include <deque>
#include <mutex>
#include <string>
#include <vector>

struct mosquitto;
struct mosquitto_message;

namespace weedspray::fleet {

struct MqttSettings {
  std::string host;
  int port = 1883;
  int keepalive_s = 5;
  std::string client_id;
  std::string username;  // "" = anonymous
  std::string password;
  std::string tls_cafile;  // "" = no TLS
  std::string tls_certfile;
  std::string tls_keyfile;
  std::string will_topic;                  // published "false", retained, when the link is lost
  std::vector<std::string> subscriptions;  // subscribed again on every connection
};

struct MqttEvent {
  enum class Kind { kConnected, kDisconnected, kMessage } kind = Kind::kMessage;
  std::string topic;
  std::string payload;
  bool retained = false;  // a retained message, replayed by the broker on subscribing
};

class MqttLink {
 public:
  // Sets up the client and starts connecting in the background. Throws std::runtime_error
  // on settings libmosquitto refuses (a TLS file missing, ...).
  explicit MqttLink(MqttSettings settings);
  ~MqttLink();
  MqttLink(const MqttLink&) = delete;
  MqttLink& operator=(const MqttLink&) = delete;

  // Readable when events wait (for sd_event_add_io).
  [[nodiscard]] int event_fd() const { return event_fd_; }
  [[nodiscard]] std::deque<MqttEvent> take();

  // QoS 1 unless told (0 for samples a retry would deliver too late). Returns false when
  // libmosquitto refuses it (not connected: the message is lost, the state is published again
  // on the next connection).
  bool publish(const std::string& topic, const std::string& payload, bool retain, int qos = 1);

  // An orderly goodbye: the broker publishes the last will at once (MQTT 5 reason 0x04).
  void disconnect_with_will();

 private:
  static void on_connect(mosquitto*, void* self, int result);
  static void on_disconnect(mosquitto*, void* self, int result);
  static void on_message(mosquitto*, void* self, const mosquitto_message* message);
  void post(MqttEvent event);

  MqttSettings settings_;
  mosquitto* client_ = nullptr;
  int event_fd_ = -1;
  std::mutex mutex_;
  std::deque<MqttEvent> events_;
};

// The first line of a password file. Throws std::runtime_error naming the file.
[[nodiscard]] std::string read_password_file(const std::string& path);

}  // namespace weedspray::fleet
