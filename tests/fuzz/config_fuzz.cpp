// SPDX-License-Identifier: Apache-2.0
// The configuration loader on arbitrary TOML text: every input is either a Config or a
// ConfigError naming what is wrong. Anything else - another exception, a crash, a sanitizer
// report - is a bug. A second document exercises the drop-in merge.
#include <cstddef>
#include <cstdint>
#include <string>

#include "daemon/config/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::size_t split = text.find("\n#--\n");
  try {
    if (split == std::string::npos) {
      (void)weedspray::daemon::load_config_from_strings({{"weedspray.toml", text}});
    } else {
      (void)weedspray::daemon::load_config_from_strings(
          {{"weedspray.toml", text.substr(0, split)},
           {"conf.d/50-fuzz.toml", text.substr(split + 5)}});
    }
  } catch (const weedspray::daemon::ConfigError&) {
  }
  return 0;
}
