// SPDX-License-Identifier: Apache-2.0
// The configuration's sections [daemon] [boom] [[camera]] [vision] [spray] [pwm] [pressure]: what
// the sprayer does and how fast. Part of Config (config.hpp); defaults, ranges and documentation
// are in the key table (config_keys_operation.cpp).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "vision/weed_source.hpp"

namespace weedspray::daemon {

struct DaemonSection {
  bool autostart;
  std::string log_level;  // trace|debug|info|warn|error
  std::string state_dir;
  double status_max_rate_hz;     // PropertiesChanged at most this often
  double input_stale_timeout_s;  // any live input older than this -> valves off
  int cpu_wakeup_latency_us;     // PM QoS request while running; -1 = none
};

struct BoomSection {
  int nozzles;
  double nozzle_width_m;
  double valve_open_delay_s;
  double valve_close_delay_s;
};

struct CameraSection {
  std::string device;
  int width;
  int height;
  double fps;
  std::string format;   // YUYV|MJPG|RGB3|GREY
  int exposure_us;      // 0 = automatic
  int white_balance_k;  // 0 = the camera's own setting
  double mount_height_m;
  double tilt_deg;  // optical axis from vertical, looking forward
  double vfov_deg;
  double distance_to_nozzles_m;  // nozzle line behind the camera's nadir
  double ground_mm_per_px;       // 0 = from mount_height_m, tilt_deg, vfov_deg and height
  int first_nozzle;
  int nozzle_count;
};

struct VisionSection {
  std::string index;
  std::string threshold;
  int fixed_threshold;
  int grid_rows;
  std::string weed_source;  // vegetation|inter_row|dnn|hybrid|plants
  double row_band_cm;       // inter_row: width of a crop-row band on the ground
  double crop_margin_cm;    // hybrid: the network's crop mask grown by this much
  double min_plant_cm2;     // plants: smaller connected vegetation is not a plant
  std::string model;        // ONNX file (dnn, hybrid); relative: see resolve_model_path()
  int model_input_width;
  int model_input_height;
  std::vector<double> model_mean;  // R, G, B on the 0..255 scale
  double model_scale;
  bool model_rgb;
  std::vector<std::string> model_classes;
  int soil_class;
  int crop_class;
  int weed_class;
  int max_network_pixels;  // largest network input the ground scale may ask for
};

// The weed model a configuration uses (dnn, hybrid), read once at load: the file found and its
// bytes, which every camera's vision pipeline is built from.
struct LoadedModel {
  std::filesystem::path path;
  std::vector<std::uint8_t> onnx;
  std::filesystem::path description_path;  // NAME.json beside NAME.onnx
  vision::DnnModelSpec spec;       // the JSON's spec with the configuration's overrides applied
  std::string licence;             // as the JSON states it
  double dataset_mm_per_px = 0.0;  // its training photos' ground scale; 0 = not stated
};

struct SpraySection {
  // The dose at full weed cover in L/ha; > 0 sets nominal_flow_l_per_min from it at load.
  double target_rate_l_per_ha;
  double nominal_flow_l_per_min;
  double nominal_speed_m_per_s;
  double max_density;
  double calibration_slope_l_per_min_per_pct;
  double calibration_offset_l_per_min;
  double calibration_pressure_mpa;
  double duty_min_pct;
  double duty_max_pct;
  int quantiser_levels;
  double hysteresis_pct;
  double decision_threshold;
  std::string low_duty_policy;  // "raise_to_min" | "close"
  bool pressure_compensation;
};

struct PwmSection {
  double frequency_hz;
  bool staggered;
  std::string order;  // outer_first|inner_first|left_to_right
  double min_on_s;
  double min_off_s;
  double dead_man_s;
};

struct PressureSection {
  double setpoint_mpa;
  std::string controller;  // fuzzy_pid|pid
  double loop_hz;
  double kp;
  double ki;
  double kd;
  double cp;
  double ci;
  double cd;
  double range_mpa;       // Vmax - Vmin for the fuzzy quantisation
  double sensor_min_mpa;  // pressure at 4 mA
  double sensor_max_mpa;  // pressure at 20 mA
  double output_min;      // return-valve closure 0..1
  double output_max;
};

}  // namespace weedspray::daemon
