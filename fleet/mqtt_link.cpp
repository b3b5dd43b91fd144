// SPDX-License-Identifier: Apache-2.0
#include "fleet/mqtt_link.hpp"

#include <mosquitto.h>
#include <mqtt_protocol.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <utility>

namespace weedspray::fleet {
namespace {

constexpr int kQos = 1;
constexpr const char* kOffline = "false";

void check(int rc, const char* what) {
  if (rc == MOSQ_ERR_SUCCESS) return;
  std::string text = what;
  text += ": ";
  text += rc == MOSQ_ERR_ERRNO ? "system error" : mosquitto_strerror(rc);
  throw std::runtime_error(text);
}

const char* or_null(const std::string& text) {
  return text.empty() ? nullptr : text.c_str();
}

}  // namespace

std::string read_password_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot be read (fleet.password_file)");
  std::string line;
  std::getline(in, line);
  return line;
}

MqttLink::MqttLink(MqttSettings settings) : settings_(std::move(settings)) {
  event_fd_ = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (event_fd_ < 0) throw std::runtime_error("cannot make an eventfd");
  mosquitto_lib_init();
  client_ = mosquitto_new(settings_.client_id.c_str(), true, this);
  if (client_ == nullptr) throw std::runtime_error("cannot make the MQTT client");
  check(mosquitto_int_option(client_, MOSQ_OPT_PROTOCOL_VERSION, MQTT_PROTOCOL_V5), "MQTT 5");
  check(mosquitto_will_set(client_, settings_.will_topic.c_str(), 5, kOffline, kQos, true),
        "the last will");
  if (!settings_.username.empty()) {
    check(
        mosquitto_username_pw_set(client_, settings_.username.c_str(), or_null(settings_.password)),
        "the broker credentials");
  }
  if (!settings_.tls_cafile.empty()) {
    check(
        mosquitto_tls_set(client_, settings_.tls_cafile.c_str(), nullptr,
                          or_null(settings_.tls_certfile), or_null(settings_.tls_keyfile), nullptr),
        "TLS (fleet.tls_cafile, tls_certfile, tls_keyfile)");
  }
  mosquitto_connect_callback_set(client_, &MqttLink::on_connect);
  mosquitto_disconnect_callback_set(client_, &MqttLink::on_disconnect);
  mosquitto_message_callback_set(client_, &MqttLink::on_message);
  check(mosquitto_reconnect_delay_set(client_, 1, 10, true), "the reconnection delay");
  // A broker not up yet is no error: the network thread keeps trying.
  const int rc = mosquitto_connect_async(client_, settings_.host.c_str(), settings_.port,
                                         settings_.keepalive_s);
  if (rc != MOSQ_ERR_SUCCESS && rc != MOSQ_ERR_ERRNO) check(rc, "connecting to the broker");
  check(mosquitto_loop_start(client_), "the MQTT network thread");
}

MqttLink::~MqttLink() {
  if (client_ != nullptr) {
    mosquitto_disconnect(client_);
    mosquitto_loop_stop(client_, false);  // once what is queued (the goodbye) is sent
    mosquitto_destroy(client_);
  }
  mosquitto_lib_cleanup();
  if (event_fd_ >= 0) close(event_fd_);
}

void MqttLink::post(MqttEvent event) {
  {
    std::lock_guard lock(mutex_);
    events_.push_back(std::move(event));
  }
  const std::uint64_t one = 1;
  (void)!write(event_fd_, &one, sizeof one);
}

std::deque<MqttEvent> MqttLink::take() {
  std::uint64_t count = 0;
  (void)!read(event_fd_, &count, sizeof count);
  std::lock_guard lock(mutex_);
  return std::exchange(events_, {});
}

void MqttLink::on_connect(mosquitto* client, void* self, int result) {
  auto* link = static_cast<MqttLink*>(self);
  if (result != 0) return;  // refused (credentials, ...): the network thread tries again
  for (const auto& topic : link->settings_.subscriptions) {
    mosquitto_subscribe(client, nullptr, topic.c_str(), kQos);
  }
  link->post({MqttEvent::Kind::kConnected, "", "", false});
}

void MqttLink::on_disconnect(mosquitto*, void* self, int) {
  static_cast<MqttLink*>(self)->post({MqttEvent::Kind::kDisconnected, "", "", false});
}

void MqttLink::on_message(mosquitto*, void* self, const mosquitto_message* message) {
  const auto* bytes = static_cast<const char*>(message->payload);
  static_cast<MqttLink*>(self)->post(
      {MqttEvent::Kind::kMessage, message->topic,
       std::string(bytes, bytes + static_cast<std::size_t>(message->payloadlen)), message->retain});
}

bool MqttLink::publish(const std::string& topic, const std::string& payload, bool retain, int qos) {
  return mosquitto_publish(client_, nullptr, topic.c_str(), static_cast<int>(payload.size()),
                           payload.data(), qos, retain) == MOSQ_ERR_SUCCESS;
}

void MqttLink::disconnect_with_will() {
  mosquitto_disconnect_v5(client_, MQTT_RC_DISCONNECT_WITH_WILL_MSG, nullptr);
}

}  // namespace weedspray::fleet
