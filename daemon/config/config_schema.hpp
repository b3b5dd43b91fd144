// SPDX-License-Identifier: Apache-2.0
// The one table of configuration keys: name, type, default, range, unit and documentation.
// The parser, --check-config, --dump-config and the tests (round trip, etc/weedspray.toml
// documents every key) all read this table; nothing else declares a key.
#pragma once

#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "daemon/config/config.hpp"

namespace weedspray::daemon {

enum class KeyType { kBool, kInt, kDouble, kString, kEnum, kIntList, kStringList, kDoubleList };

template <class Root>
using FieldAccess =
    std::variant<bool& (*)(Root&), int& (*)(Root&), double& (*)(Root&), std::string& (*)(Root&),
                 std::vector<int>& (*)(Root&), std::vector<std::string>& (*)(Root&),
                 std::vector<double>& (*)(Root&)>;

using DefaultValue = std::variant<bool, int, double, std::string, std::vector<int>,
                                  std::vector<std::string>, std::vector<double>>;

template <class Root>
struct KeySpec {
  KeySpec(std::string_view section, std::string_view name, FieldAccess<Root> field,
          DefaultValue default_value, double min, double max, std::string_view unit,
          std::string_view doc, std::vector<std::string_view> choices = {})
      : section(section),
        name(name),
        field(field),
        default_value(std::move(default_value)),
        min(min),
        max(max),
        unit(unit),
        doc(doc),
        choices(std::move(choices)) {}

  std::string_view section;  // "pressure"; "camera" for keys of each [[camera]]
  std::string_view name;     // "setpoint_mpa"
  FieldAccess<Root> field;
  DefaultValue default_value;
  double min;  // numeric range (ints, doubles, every element of number lists)
  double max;
  std::string_view unit;
  std::string_view doc;
  std::vector<std::string_view> choices;  // allowed values of an enum key (empty otherwise)

  [[nodiscard]] KeyType type() const;
  [[nodiscard]] std::string full_name() const;  // "pressure.setpoint_mpa"
};

// Keys of the plain sections ([daemon], [boom], [pressure] ...).
const std::vector<KeySpec<Config>>& config_keys();
// The plain key `full_name` ("spray.decision_threshold"); std::out_of_range when none is.
const KeySpec<Config>& config_key(std::string_view full_name);
// "" when `value` lies in that key's range, else why not: the value, the key and its range.
std::string outside_key_range(std::string_view full_name, double value);
// Keys of each [[camera]] entry.
const std::vector<KeySpec<CameraSection>>& camera_keys();

[[nodiscard]] std::string_view key_type_name(KeyType type);

// The [vision] keys that override a weed model's own spec (its NAME.json): unset, the model's
// value holds, so the default file leaves them commented out.
[[nodiscard]] bool overrides_model_spec(std::string_view full_name);

// The trip limits of the alarms that are faults (pump off, valves closed): a live reload keeps
// their running value, a restart applies a change (config/live_reload.hpp).
[[nodiscard]] bool is_safety_limit(std::string_view full_name);

}  // namespace weedspray::daemon

namespace weedspray::daemon {

// The whole key table as a commented TOML file at its defaults (etc/weedspray.toml is made
// from it): each key preceded by its documentation, type, unit, range and choices.
[[nodiscard]] std::string documented_config();

// The same table as the man page weedspray.toml(5), in roff; `version` goes in its header.
[[nodiscard]] std::string config_reference_man(std::string_view version);

}  // namespace weedspray::daemon
