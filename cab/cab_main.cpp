// SPDX-License-Identifier: Apache-2.0
// weedspray-cab: the cab's page for a phone or tablet. Reads the machine's boards from the MQTT
// broker ([fleet] of the configuration: broker, machine, credentials, TLS) and serves one page
// ([cab]: where it listens) that shows them and publishes the guarded Start and Stop, and the
// dose, on the machine's command topic. A program of its own, unprivileged, no D-Bus
// (docs/fleet.md).
#include <poll.h>
#include <signal.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <thread>

#include <httplib.h>
#include <CLI/CLI.hpp>

#include "cab/machine_view.hpp"
#include "cab/picture_store.hpp"
#include "daemon/config/config.hpp"
#include "fleet/broker_settings.hpp"

namespace {

using namespace weedspray;

// Folds the broker's messages into the view until `stop`.
void follow_broker(fleet::MqttLink& mqtt, cab::MachineView& view, cab::PictureStore& pictures,
                   const std::string& online_topic, const std::atomic<bool>& stop) {
  while (!stop) {
    pollfd fd{mqtt.event_fd(), POLLIN, 0};
    if (poll(&fd, 1, 200) <= 0) continue;
    for (const auto& event : mqtt.take()) {
      switch (event.kind) {
        case fleet::MqttEvent::Kind::kConnected:
          view.set_broker_connected(true);
          mqtt.publish(online_topic, "true", true);
          break;
        case fleet::MqttEvent::Kind::kDisconnected:
          view.set_broker_connected(false);
          break;
        case fleet::MqttEvent::Kind::kMessage:
          if (!pictures.apply(event.topic, event.payload)) view.apply(event.topic, event.payload);
          break;
      }
    }
  }
}

// POST /api/command {"command": "start"|"stop"|"rate", "confirmed": true}, with "l_per_ha" for
// rate: the page's guarded buttons and its dose, published for every board on
// weedspray/<machine>/cmd (the daemons check the dose).
void handle_command(const httplib::Request& request, httplib::Response& response,
                    fleet::MqttLink& mqtt, const std::string& command_topic) {
  static std::atomic<unsigned> sequence{0};
  const auto body = nlohmann::json::parse(request.body, nullptr, false);
  const auto reply = [&](int status, bool ok, const std::string& message) {
    response.status = status;
    response.set_content(nlohmann::json{{"ok", ok}, {"message", message}}.dump(),
                         "application/json");
  };
  if (!body.is_object() || !body.contains("command") || !body["command"].is_string()) {
    return reply(400, false,
                 "expected {\"command\": \"start\"|\"stop\"|\"rate\", \"confirmed\": true}");
  }
  const std::string command = body["command"];
  if (command != "start" && command != "stop" && command != "rate") {
    return reply(400, false, "the page sends start, stop and rate only");
  }
  const bool rate = command == "rate";
  if (rate && !(body.contains("l_per_ha") && body["l_per_ha"].is_number())) {
    return reply(400, false, "rate needs the number \"l_per_ha\"");
  }
  if (body.value("confirmed", false) != true) {
    return reply(400, false, "not confirmed");
  }
  const std::string id = "cab-" + std::to_string(++sequence);
  nlohmann::json message{{"command", command}, {"id", id}};
  if (rate) message["l_per_ha"] = body["l_per_ha"];
  if (!mqtt.publish(command_topic, message.dump(), false)) {
    return reply(503, false, "the broker is not connected");
  }
  std::fprintf(stderr, "weedspray-cab: %s sent to the machine (%s)\n", command.c_str(), id.c_str());
  reply(200, true, id);
}

std::filesystem::path web_dir_or_source(const std::string& given) {
  if (!given.empty()) return given;
  if (std::filesystem::exists(WEEDSPRAY_CAB_WEB_DIR)) return WEEDSPRAY_CAB_WEB_DIR;
  return WEEDSPRAY_CAB_SOURCE_WEB_DIR;  // a build tree runs without installing
}

int run(const daemon::Config& config, const std::filesystem::path& web_dir) {
  const auto& f = config.fleet;
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);  // inherited by every thread made below

  cab::MachineView view(f.machine);
  cab::PictureStore pictures(f.machine);
  const std::string machine_topic = "weedspray/" + f.machine;
  fleet::MqttLink mqtt(fleet::broker_settings(f, "weedspray-" + f.machine + "-cab",
                                              machine_topic + "/cab_online",
                                              {machine_topic + "/+/+"}));
  std::atomic<bool> stop{false};
  std::thread broker_thread(follow_broker, std::ref(mqtt), std::ref(view), std::ref(pictures),
                            machine_topic + "/cab_online", std::cref(stop));

  httplib::Server server;
  if (!server.set_mount_point("/", web_dir.string())) {
    std::fprintf(stderr, "weedspray-cab: %s: no such folder\n", web_dir.c_str());
    stop = true;
    broker_thread.join();
    return 1;
  }
  server.Get("/api/machine", [&](const httplib::Request&, httplib::Response& response) {
    response.set_header("Cache-Control", "no-store");
    auto machine = view.to_json();
    const auto latest = pictures.to_json();
    for (auto it = latest.begin(); it != latest.end(); ++it) {
      machine["boards"][it.key()]["picture"] = it.value();
    }
    response.set_content(machine.dump(), "application/json");
  });
  // The board's latest live-view picture (404 until one came).
  server.Get(R"(/api/board/([A-Za-z0-9_-]+)/picture\.png)",
             [&](const httplib::Request& request, httplib::Response& response) {
               response.set_header("Cache-Control", "no-store");
               if (auto png = pictures.png(request.matches[1])) {
                 response.set_content(std::move(*png), "image/png");
               } else {
                 response.status = 404;
                 response.set_content("no picture from this board yet\n", "text/plain");
               }
             });
  const std::string command_topic = machine_topic + "/cmd";
  server.Post("/api/command", [&](const httplib::Request& request, httplib::Response& response) {
    handle_command(request, response, mqtt, command_topic);
  });
  std::thread signal_thread([&] {
    int signal = 0;
    sigwait(&signals, &signal);
    server.stop();
  });
  std::fprintf(stderr, "weedspray-cab: machine %s, broker %s:%d, page on http://%s:%d/\n",
               f.machine.c_str(), f.host.c_str(), f.port, config.cab.listen_address.c_str(),
               config.cab.port);
  const bool listened = server.listen(config.cab.listen_address, config.cab.port);
  if (!listened) {
    std::fprintf(stderr, "weedspray-cab: cannot listen on %s:%d\n",
                 config.cab.listen_address.c_str(), config.cab.port);
    pthread_kill(signal_thread.native_handle(), SIGTERM);
  }
  signal_thread.join();
  stop = true;
  broker_thread.join();
  mqtt.disconnect_with_will();
  return listened ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"weedspray-cab: the cab's page for the whole machine"};
  std::string config_path = daemon::kDefaultConfigPath;
  std::string web_dir;
  app.add_option("--config", config_path, "the configuration file ([fleet] and [cab])");
  app.add_option("--web-dir", web_dir, "the page's files (default: the installed ones)");
  CLI11_PARSE(app, argc, argv);
  try {
    return run(daemon::load_config_without_vision(config_path), web_dir_or_source(web_dir));
  } catch (const std::exception& error) {
    std::fprintf(stderr, "weedspray-cab: %s\n", error.what());
    return 1;
  }
}
