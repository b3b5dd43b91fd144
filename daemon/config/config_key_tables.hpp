// SPDX-License-Identifier: Apache-2.0
// The key table behind config_keys() (config_schema.hpp), in four files by concern; each
// appends its sections' keys in the order the shipped file and weedspray.toml(5) list them.
#pragma once

#include <string>
#include <vector>

#include "daemon/config/config_schema.hpp"

// A captureless accessor for one member, converted to a plain function pointer so the table
// is data, not code.
#define WS_FIELD(Root, member) \
  +[](Root & r) -> auto& {     \
    return r.member;           \
  }
#define WS_KEY(section, name) #section, #name, WS_FIELD(Config, section.name)
#define WS_CAM(name) "camera", #name, WS_FIELD(CameraSection, name)

namespace weedspray::daemon::key_tables {

// [daemon] [boom] [vision] [spray] [pwm] [pressure]
void append_operation_keys(std::vector<KeySpec<Config>>& keys);
// [gpio] [adc] [dac] [analog_modbus] [flow]
void append_wiring_keys(std::vector<KeySpec<Config>>& keys);
// [calibration] [nozzle_health] [wheel] [speed] [gnss] [turn] [modbus]
void append_measurement_keys(std::vector<KeySpec<Config>>& keys);
// [alarms] [log] [sim] [fleet] [cab]
void append_supervision_keys(std::vector<KeySpec<Config>>& keys);

}  // namespace weedspray::daemon::key_tables
