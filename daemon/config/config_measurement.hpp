// SPDX-License-Identifier: Apache-2.0
// The configuration's sections [calibration] [nozzle_health] [wheel] [speed] [gnss] [turn]
// [modbus]: what the machine measures. Part of Config (config.hpp); defaults, ranges and
// documentation are in the key table (config_keys_measurement.cpp).
#pragma once

#include <string>
#include <vector>

namespace weedspray::daemon {

// Calibrations run from the daemon (sprayctl calibrate nozzles; daemon/sprayer/calibration_run).
struct CalibrationSection {
  std::vector<double> duties_pct;  // the nozzle sweep's duties
  double settle_s;                 // skipped at each point (valve, pressure, meter settling)
  double measure_s;                // counted at each point
  double min_r_squared;            // a nozzle's fit below this: the [spray] line stays in use
  bool full_open;                  // also meter each nozzle held open (its full-open flow)
  double meter_max_change_pct;     // a catch test's K this far off flow.pulses_per_litre: refused
};

// Per-nozzle health from the line meter while spraying (control/nozzle_health.hpp).
struct NozzleHealthSection {
  bool enabled;
  double baseline_s;
  double time_constant_s;
  std::string judge;  // band|cusum
  double alarm_fraction;
  double alarm_hold_s;
  double alarm_threshold;
  bool recheck;
  double recheck_clear_s;
  double recheck_settle_s;
  double recheck_measure_s;
  double recheck_interval_s;
  double recheck_warn_pct;
  double recheck_alarm_pct;
  double recheck_stopped_m_per_s;
};

struct WheelSection {
  std::string source;  // pulses|fixed
  double pulses_per_metre;
  double fixed_speed_m_per_s;
};

// How the ground speed is found (daemon/sprayer/ground_speed.hpp).
struct SpeedSection {
  std::string source;       // wheel|gnss|fixed|fleet
  double shared_timeout_s;  // fleet: no sample from the owning board for this long is a loss
};

// The GNSS receiver, read through gpsd.
struct GnssSection {
  bool enabled;
  std::string source;  // "gpsd" (this board's receiver) | "fleet" (speed_from's fix)
  std::string host;
  int port;
  double lost_fix_timeout_s;   // no usable fix for this long: gnss_fix_lost, speed falls back
  double first_fix_timeout_s;  // after start: the receiver's time to find its first fix
  double reconnect_max_s;      // ceiling of the reconnection backoff while gpsd is away
  // Where the antenna sits relative to the middle of the nozzle line (maps place each
  // nozzle's patch from it): ahead along the direction of travel, and right of the centre.
  double antenna_ahead_of_nozzles_m;
  double antenna_right_of_centre_m;
};

// Turn compensation: on a curve each nozzle moves at its own ground speed
// v_i = v + yaw_rate x lateral offset (daemon/sprayer/turn_speed.hpp).
struct TurnSection {
  bool compensation;
  std::string yaw_source;    // gnss|imu|none
  std::string imu_device;    // IIO gyro: "iio:deviceN", a directory, or its name
  std::string imu_axis;      // x|y|z: the sensor axis that is vertical on the machine
  bool imu_axis_up;          // that axis points up (else down)
  double min_speed_m_per_s;  // below: the course is noise, yaw rate taken as 0
  double yaw_filter_s;       // time constant of the yaw-rate low-pass
};

struct ModbusSection {
  bool enabled;
  std::string device;
  int baud;
  std::string parity;  // N|E|O
  int slave_id;
  int tank_register;
  double tank_scale_pct_per_count;
  double poll_period_s;
  double timeout_s;
};

}  // namespace weedspray::daemon
