// SPDX-License-Identifier: Apache-2.0
#include "daemon/config/config_schema.hpp"

#include "daemon/config/config_key_tables.hpp"

#include <algorithm>
#include <array>

#include <climits>
#include <sstream>
#include <stdexcept>

// GCC 12 reports a false -Wmaybe-uninitialized inside std::variant<..., std::string> when the
// key table is built (GCC bug 107138 and relatives); the table is plain constant data.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace weedspray::daemon {

template <class Root>
KeyType KeySpec<Root>::type() const {
  switch (field.index()) {
    case 0:
      return KeyType::kBool;
    case 1:
      return KeyType::kInt;
    case 2:
      return KeyType::kDouble;
    case 3:
      return choices.empty() ? KeyType::kString : KeyType::kEnum;
    case 4:
      return KeyType::kIntList;
    case 5:
      return KeyType::kStringList;
    default:
      return KeyType::kDoubleList;
  }
}

template <class Root>
std::string KeySpec<Root>::full_name() const {
  return std::string(section) + "." + std::string(name);
}

template struct KeySpec<Config>;
template struct KeySpec<CameraSection>;

std::string_view key_type_name(KeyType type) {
  switch (type) {
    case KeyType::kBool:
      return "boolean";
    case KeyType::kInt:
      return "integer";
    case KeyType::kDouble:
      return "number";
    case KeyType::kString:
      return "string";
    case KeyType::kEnum:
      return "choice";
    case KeyType::kIntList:
      return "array of integers";
    case KeyType::kStringList:
      return "array of strings";
    case KeyType::kDoubleList:
      return "array of numbers";
  }
  return "?";
}

const std::vector<KeySpec<Config>>& config_keys() {
  static const std::vector<KeySpec<Config>> keys = [] {
    std::vector<KeySpec<Config>> all;
    key_tables::append_operation_keys(all);
    key_tables::append_wiring_keys(all);
    key_tables::append_measurement_keys(all);
    key_tables::append_supervision_keys(all);
    return all;
  }();
  return keys;
}

const std::vector<KeySpec<CameraSection>>& camera_keys() {
  // clang-format off
  static const std::vector<KeySpec<CameraSection>> keys = {
    {WS_CAM(device), std::string("/dev/video0"), 0, 0, "path", "V4L2 device"},
    {WS_CAM(width), 1280, 16, 8192, "px", "frame width"},
    {WS_CAM(height), 800, 16, 8192, "px", "frame height"},
    {WS_CAM(fps), 30.0, 0.1, 240, "Hz", "frame rate requested"},
    {WS_CAM(format), std::string("YUYV"), 0, 0, "", "pixel format",
     {"YUYV", "MJPG", "RGB3", "GREY"}},
    {WS_CAM(exposure_us), 0, 0, 1000000, "us", "fixed exposure (0 = automatic)"},
    {WS_CAM(white_balance_k), 0, 0, 15000, "K",
     "fixed white balance colour temperature, automatic white balance off: vegetation indices "
     "compare colours, so a fixed balance keeps thresholds steady (0 = leave the camera's own "
     "setting)"},
    {WS_CAM(mount_height_m), 1.0, 0.1, 10, "m", "lens height above ground"},
    {WS_CAM(tilt_deg), 30.0, 0, 80, "deg", "optical axis from vertical, looking forward"},
    {WS_CAM(vfov_deg), 40.0, 1, 170, "deg", "vertical (along travel) field of view"},
    {WS_CAM(ground_mm_per_px), 0.0, 0, 100, "mm",
     "ground size of one pixel at the image centre, across travel; 0 = from mount_height_m, "
     "tilt_deg and vfov_deg (square pixels). The weed model's input is resampled to the ground "
     "scale it learnt at"},
    {WS_CAM(distance_to_nozzles_m), 1.2, 0, 50, "m",
     "nozzle line behind the camera's nadir (ground point under the lens), along travel"},
    {WS_CAM(first_nozzle), 0, 0, 31, "", "first nozzle (0-based) this camera steers"},
    {WS_CAM(nozzle_count), 4, 1, 32, "", "number of consecutive nozzles this camera steers"},
  };
  // clang-format on
  return keys;
}

const KeySpec<Config>& config_key(std::string_view full_name) {
  const auto& keys = config_keys();
  const auto found = std::find_if(keys.begin(), keys.end(),
                                  [&](const auto& spec) { return spec.full_name() == full_name; });
  if (found == keys.end())
    throw std::out_of_range("no configuration key " + std::string(full_name));
  return *found;
}

std::string outside_key_range(std::string_view full_name, double value) {
  const auto& spec = config_key(full_name);
  if (value >= spec.min && value <= spec.max) return {};  // a NaN is outside
  std::ostringstream message;
  message << value << " outside " << full_name << "'s range " << spec.min << ".." << spec.max;
  if (!spec.unit.empty()) message << " " << spec.unit;
  return message.str();
}

bool overrides_model_spec(std::string_view full_name) {
  static constexpr std::array<std::string_view, 9> kKeys = {
      "vision.model_input_width", "vision.model_input_height", "vision.model_mean",
      "vision.model_scale",       "vision.model_rgb",          "vision.model_classes",
      "vision.soil_class",        "vision.crop_class",         "vision.weed_class"};
  return std::find(kKeys.begin(), kKeys.end(), full_name) != kKeys.end();
}

bool is_safety_limit(std::string_view full_name) {
  static constexpr std::array<std::string_view, 12> kKeys = {
      "alarms.over_pressure_mpa",     "alarms.sensor_fault_low_ma",
      "alarms.sensor_fault_high_ma",  "alarms.sensor_fault_hold_s",
      "alarms.blocked_pressure_mpa",  "alarms.blocked_flow_l_per_min",
      "alarms.no_flow_l_per_min",     "alarms.debounce_s",
      "alarms.tank_empty_pct",        "alarms.camera_stall_s",
      "alarms.closed_flow_l_per_min", "alarms.closed_flow_settle_s"};
  return std::find(kKeys.begin(), kKeys.end(), full_name) != kKeys.end();
}

}  // namespace weedspray::daemon
