// SPDX-License-Identifier: Apache-2.0
// The simulated machine the Sprayer's loop tests spray on: default config, constant speed, sim
// backends (swap an output or converter in `backends` for a wrapper before start()), pump and
// valves enabled.
#pragma once

#include <optional>
#include <string>

#include "daemon/backends/backends.hpp"
#include "daemon/sprayer/sprayer.hpp"

namespace weedspray::daemon {

struct SprayingMachine {
  // speed_m_per_s > 0: the constant speed (else sim.speed_max_m_per_s's default).
  explicit SprayingMachine(double speed_m_per_s = 0.0) {
    config.sim.speed_profile = "constant";
    if (speed_m_per_s > 0.0) config.sim.speed_max_m_per_s = speed_m_per_s;
    Options options;
    options.sim = true;
    backends = make_sim_backends(config, options);
  }
  void start() {
    sprayer.emplace(config, backends);
    params = live_params_from(config);
    params.pump_enabled = true;
    params.valves_enabled = true;
    sprayer->set_params(params);
    sprayer->start();
  }
  bool pump_on() const { return backends.describe_outputs().find("pump=1") != std::string::npos; }
  Config config = default_config();
  Backends backends;
  std::optional<Sprayer> sprayer;
  LiveParams params;
};

}  // namespace weedspray::daemon
