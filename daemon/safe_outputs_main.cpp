// weedspray-safe-outputs: writes every configured output's safe value and exits; the unit's
// ExecStopPost after every exit of weedsprayd, kill -9 included (daemon/CMakeLists.txt says why
// it is not weedsprayd --safe-outputs, which does the same).
#include <CLI/CLI.hpp>
#include <string>

#include "daemon/backends/backends.hpp"
#include "daemon/config/config.hpp"

int main(int argc, char** argv) {
  std::string config_path = weedspray::daemon::kDefaultConfigPath;
  CLI::App app{
      "weedspray-safe-outputs: write every output of the configuration at its safe value "
      "(valves and pump off, buzzer/LED/heartbeat low, return valve at dac.safe_value)"};
  app.add_option("--config", config_path, "main configuration file (drop-ins: conf.d/)");
  CLI11_PARSE(app, argc, argv);
  return weedspray::daemon::write_safe_outputs(config_path, "weedspray-safe-outputs");
}
