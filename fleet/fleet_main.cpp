// SPDX-License-Identifier: Apache-2.0
// weedspray-fleet: joins this board to its machine over an MQTT broker ([fleet] of the
// daemon's configuration file; docs/fleet.md). An unprivileged program beside weedsprayd: it
// reads the daemon only over D-Bus and steers it only through the daemon's D-Bus methods.
#include <signal.h>
#include <systemd/sd-event.h>

#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "daemon/config/config.hpp"
#include "fleet/bridge.hpp"
#include "fleet/broker_settings.hpp"
#include "fleet/motion_publisher.hpp"
#include "fleet/picture_publisher.hpp"
#include "fleet/shared_motion_feed.hpp"

namespace {

using namespace weedspray;

int on_signal(sd_event_source* source, const signalfd_siginfo*, void*) {
  return sd_event_exit(sd_event_source_get_event(source), 0);
}

int on_mqtt(sd_event_source* source, int, uint32_t, void* userdata) {
  auto* bridge = static_cast<fleet::Bridge*>(userdata);
  bridge->on_mqtt_events();
  if (bridge->bus_closed()) return sd_event_exit(sd_event_source_get_event(source), 1);
  return 0;
}

int run(const daemon::Config& config, bool user_bus) {
  // Blocked before the MQTT network thread starts, which inherits the mask: sd-event takes
  // them from a signalfd, so no thread dies of them.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  sigprocmask(SIG_BLOCK, &signals, nullptr);
  const auto& f = config.fleet;
  const fleet::Topics topics(f.machine, f.board);
  std::vector<std::string> subscriptions{topics.machine_commands(), topics.board_commands(),
                                         topics.every_online()};
  const std::string motion_topic =
      f.speed_from.empty() ? std::string() : topics.other_board(f.speed_from, "motion");
  if (!motion_topic.empty()) subscriptions.push_back(motion_topic);
  fleet::MqttLink mqtt(fleet::broker_settings(f, "weedspray-" + f.machine + "-" + f.board,
                                              topics.board("online"), std::move(subscriptions)));
  fleet::Bridge bridge(mqtt,
                       {f.machine, f.board, config.boom.nozzles, config.boom.nozzle_width_m,
                        f.first_nozzle_offset_m, f.commands},
                       {f.on_board_lost == "stop", f.on_broker_lost == "stop"});
  sd_event* event = nullptr;
  if (sd_event_default(&event) < 0) throw std::runtime_error("cannot make the event loop");
  std::unique_ptr<sd_event, decltype(&sd_event_unref)> event_owner(event, &sd_event_unref);
  sd_event_add_signal(event, nullptr, SIGTERM, on_signal, nullptr);
  sd_event_add_signal(event, nullptr, SIGINT, on_signal, nullptr);
  sd_event_add_io(event, nullptr, mqtt.event_fd(), EPOLLIN, on_mqtt, &bridge);
  fleet::DaemonClient daemon(event, user_bus, bridge);
  bridge.attach(daemon);
  fleet::SharedMotionFeed shared_motion(daemon, motion_topic);
  bridge.take_shared_motion(shared_motion);
  const fleet::PicturePublisher pictures(event, f.picture_interval_s, daemon, mqtt, topics);
  const fleet::MotionPublisher motion(event, f.motion_rate_hz, daemon, mqtt, topics);
  std::fprintf(stderr, "weedspray-fleet: board %s of machine %s, broker %s:%d\n", f.board.c_str(),
               f.machine.c_str(), f.host.c_str(), f.port);
  int status = sd_event_loop(event);
  if (bridge.bus_closed()) status = 1;
  bridge.goodbye();
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"weedspray-fleet: joins this board to its machine over an MQTT broker"};
  std::string config_path = daemon::kDefaultConfigPath;
  bool user_bus = false;
  app.add_option("--config", config_path, "the daemon's configuration file ([fleet])");
  app.add_flag("--user", user_bus, "reach weedsprayd on the session bus (weedsprayd --user)");
  CLI11_PARSE(app, argc, argv);
  try {
    const daemon::Config config = daemon::load_config_without_vision(config_path);
    if (!config.fleet.enabled) {
      std::fprintf(stderr, "weedspray-fleet: fleet.enabled is false in %s: nothing to do\n",
                   config_path.c_str());
      return 0;
    }
    return run(config, user_bus);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "weedspray-fleet: %s\n", error.what());
    return 1;
  }
}
