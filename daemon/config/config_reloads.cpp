// SPDX-License-Identifier: Apache-2.0
#include "daemon/config/config_reloads.hpp"

#include <spdlog/spdlog.h>

#include "daemon/config/live_reload.hpp"
#include "daemon/config/run_config.hpp"
#include "daemon/logging.hpp"
#include "daemon/test_crash_hook.hpp"

namespace weedspray::daemon {
namespace {

CommandResult refuse(const std::string& why) {
  spdlog::error("reload refused, running configuration kept: {}", why);
  return {kErrorConfig, why};
}

}  // namespace

void ConfigReloads::request(ReloadReply reply) {
  waiters_.push_back(std::move(reply));
  if (!job_) start();  // else the next job, once this one is applied
}

void ConfigReloads::start() {
  auto job = std::make_unique<Job>();
  job->waiters = std::exchange(waiters_, {});
  Job* running = job.get();
  job->thread = std::jthread([running, options = options_] {
    const std::chrono::milliseconds delay = test_reload_delay();
    if (delay.count() > 0) std::this_thread::sleep_for(delay);
    try {
      running->config = load_config_with_overrides(options);
    } catch (const std::exception& error) {  // ConfigError, or a conf.d that cannot be listed
      running->error = error.what();
    }
    running->done.store(true, std::memory_order_release);
  });
  job_ = std::move(job);
}

void ConfigReloads::finish() {
  if (!job_ || !job_->done.load(std::memory_order_acquire)) return;
  job_->thread.join();
  const CommandResult result = job_->config ? apply(*job_->config) : refuse(job_->error);
  std::vector<ReloadReply> waiters = std::move(job_->waiters);
  job_.reset();
  for (auto& reply : waiters) {
    if (reply) reply(result);
  }
  if (!waiters_.empty()) start();
}

CommandResult ConfigReloads::apply(const Config& fresh) {
  LiveReload reload;
  try {
    reload = apply_live_reload(running_, fresh);
  } catch (const ConfigError& error) {
    return refuse(error.what());
  }
  if (reload.restart_needed) {
    spdlog::warn(
        "reload: changes outside [spray], [alarms], pressure.setpoint_mpa and "
        "[daemon] levels take effect after a restart");
  }
  for (const auto& key : reload.kept_limits) {
    spdlog::warn("reload: {} is a safety limit: restart required, running value kept", key);
  }
  running_ = std::move(reload.config);
  operation_.reload_config();
  alarms_.set_thresholds(running_.alarms);
  set_log_level(running_.daemon.log_level);
  operation_.publish_params();
  spdlog::info("configuration reloaded from {}", options_.config_path);
  return {};
}

}  // namespace weedspray::daemon
