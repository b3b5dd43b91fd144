// SPDX-License-Identifier: Apache-2.0
// The configuration's sections [alarms] [log] [sim] [fleet] [cab]: limits, records, simulation and
// the machine's other boards. Part of Config (config.hpp); defaults, ranges and documentation are
// in the key table (config_keys_supervision.cpp).
#pragma once

#include <string>
#include <vector>

namespace weedspray::daemon {

struct AlarmsSection {
  double over_pressure_mpa;
  double sensor_fault_low_ma;
  double sensor_fault_high_ma;
  double blocked_pressure_mpa;
  double blocked_flow_l_per_min;
  double no_flow_l_per_min;
  double tank_low_pct;
  double tank_empty_pct;
  double modbus_silent_s;
  double camera_stall_s;
  double debounce_s;
  double sensor_fault_hold_s;       // a pressure-sensor fault must last this long to latch
  double timing_tolerance_ms;       // lateness that affects spraying
  int control_overrun_limit;        // such misses per second that raise control_overruns
  double calibration_drift_pct;     // the meter and the calibrated nozzles this far apart ...
  double calibration_drift_hold_s;  // ... for this long raise calibration_drift
  double closed_flow_l_per_min;     // flow above this with every valve closed ...
  double closed_flow_settle_s;      // ... closed this long: flow_with_valves_closed (Fault)
};

struct LogSection {
  std::string dir;  // "" = <daemon.state_dir>/as-applied
  int rotate_bytes;
  int keep_files;
  int min_free_mb;  // under this much free space: records_disk_full
};

struct SimSection {
  std::string speed_profile;  // constant|sine|ramp
  double speed_min_m_per_s;
  double speed_max_m_per_s;
  double speed_period_s;
  std::string images_dir;   // "" = the bundled field images
  double images_mm_per_px;  // 0 = each image is a frame as it is, of unknown ground scale
  int seed;                 // the ideal bench's plant seed (a drawn machine brings its own)
  double wheel_slip_pct;    // the simulated wheel's slip (calibrate-wheel's truth)
  std::string machine;      // drawn|ideal
  int machine_seed;         // the drawn machine: machine machine_index of the fleet machine_seed
  int machine_index;
};

// The fleet bridge (weedspray-fleet, a program of its own; the daemon ignores these keys): the
// MQTT broker, the board's name and place on the boom, credentials, TLS, accepted commands.
struct FleetSection {
  bool enabled;
  std::string host;
  int port;
  std::string machine;           // topic level: weedspray/<machine>/<board>/...
  std::string board;             // topic level
  double first_nozzle_offset_m;  // the first nozzle's place along the boom, from its left end
  int keepalive_s;               // the broker marks the board lost after 1.5 x this of silence
  std::string username;          // "" = anonymous
  std::string password_file;     // its first line is the password
  std::string tls_cafile;        // "" = no TLS
  std::string tls_certfile;      // client certificate (with tls_keyfile)
  std::string tls_keyfile;
  std::string commands;        // none|operator|admin: the command kinds taken from the broker
  std::string on_board_lost;   // continue|stop: another board of the machine lost
  std::string on_broker_lost;  // continue|stop: this board's link to the broker lost
  double picture_interval_s;   // camera 0's live-view picture published this often (0 = never)
  double motion_rate_hz;       // this board's speed and distance published this often (0 = never)
  std::string speed_from;      // the board whose motion this board's daemon takes ("" = none)
};

// The cab page (weedspray-cab, a program of its own; the daemon ignores these keys): where it
// listens. It reads the broker named in [fleet].
struct CabSection {
  std::string listen_address;
  int port;
};

}  // namespace weedspray::daemon
