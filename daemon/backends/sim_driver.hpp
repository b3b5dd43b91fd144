// SPDX-License-Identifier: Apache-2.0
// The simulated world's driver (weedsprayd --sim): the vehicle driven and the --sim-fault
// faults injected each tick, InjectSimFault, a status line a second on the console, and at
// exit the valve states and the plant's true volume for the tests.
#pragma once

#include <vector>

#include "daemon/backends/backends.hpp"
#include "daemon/backends/sim_faults.hpp"
#include "daemon/backends/world_driver.hpp"
#include "daemon/config/options.hpp"

namespace weedspray::daemon {

class SimDriver final : public WorldDriver {
 public:
  // `backends`: the simulated machine (make_sim_backends), kept by the caller.
  SimDriver(Backends& backends, const Options& options);

  bool starts_afresh() const noexcept override { return !options_.resume; }
  bool runs_without_bus(const char* why) override;
  bool tank_always_read() const noexcept override { return true; }
  bool frames_per_footprint() const noexcept override { return true; }
  std::function<double()> delivered_litres() const override;

  void start() override;
  void step(double t_s) override;
  CommandResult inject_fault(const std::string& name) override;
  void status_published(const Status& status, double t_s) override;
  void finish() override;

 private:
  void apply(const SimFault& fault);

  Backends& backends_;
  Options options_;
  std::vector<bool> faults_done_;  // per options_.sim_faults
  double last_print_s_ = -1e9;
};

}  // namespace weedspray::daemon
