// SPDX-License-Identifier: Apache-2.0
#include "daemon/backends/pick_backends.hpp"

#include <spdlog/spdlog.h>

#include "daemon/backends/sim_driver.hpp"

namespace weedspray::daemon {

std::unique_ptr<WorldDriver> pick_backends(const Config& config, const Options& options,
                                           Backends& backends) {
  backends = options.sim ? make_sim_backends(config, options) : make_hw_backends(config);
  spdlog::info("backends: {}", backends.mode);
  const std::size_t emergency = backends.register_emergency_writes();
  if (options.sim) return std::make_unique<SimDriver>(backends, options);
  spdlog::info("fatal-exit safe writes armed for {} outputs", emergency);
  return std::make_unique<WorldDriver>();
}

}  // namespace weedspray::daemon
