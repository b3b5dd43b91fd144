// SPDX-License-Identifier: Apache-2.0
// The devices the daemon drives, behind the io interfaces. backends_hw.cpp opens the board's
// (libgpiod, IIO, V4L2, libmodbus); backends_sim.cpp builds the simulated machine.
// pick_backends.cpp picks one; nothing else knows which it got.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/config/options.hpp"
#include "daemon/supervision/output_write_watch.hpp"
#include "io/analog.hpp"
#include "io/camera.hpp"
#include "io/clock.hpp"
#include "io/digital_input.hpp"
#include "io/digital_output.hpp"
#include "io/estop_input.hpp"
#include "io/gnss.hpp"
#include "io/pulse_input.hpp"
#include "io/signal_conversion.hpp"
#include "io/tank_level.hpp"
#include "io/yaw_rate_sensor.hpp"

namespace weedspray::sim::plant {
class HydraulicPlant;
}

namespace weedspray::daemon {

using SafeWriteErrors = std::array<int, kOutputRoleCount>;

struct Backends {
  io::Clock* clock = nullptr;
  io::DigitalOutputBank* valves = nullptr;     // one line per nozzle
  io::DigitalOutputBank* pump = nullptr;       // null: not wired
  io::DigitalOutputBank* buzzer = nullptr;     // null: not wired
  io::DigitalOutputBank* led = nullptr;        // null: not wired
  io::DigitalOutputBank* heartbeat = nullptr;  // null: not wired (valve thread's square wave)
  io::AnalogInput* pressure_adc = nullptr;
  io::AnalogOutput* return_valve = nullptr;
  io::PulseInput* flow = nullptr;       // null: no flow meter
  io::PulseInput* wheel = nullptr;      // null: fixed speed
  io::DigitalInput* key = nullptr;      // null: no start/stop key
  io::EstopInput* estop = nullptr;      // null: no emergency-stop input
  io::TankLevelSensor* tank = nullptr;  // null: no tank sensor
  io::GnssReceiver* gnss = nullptr;     // null: gnss.enabled = false, or its source "fleet"
  // gnss.source = "fleet": no receiver; the control loop publishes the fix that comes with the
  // shared motion samples (daemon/sprayer/shared_position.hpp).
  bool gnss_from_fleet = false;
  io::YawRateSensor* yaw_sensor = nullptr;  // null: turn.yaw_source is not "imu"
  std::vector<io::Camera*> cameras;         // one per [[camera]]
  io::CurrentLoopSensorConfig sensor{};
  io::ValveDriveConfig drive{};
  std::string mode;  // "hw" | "sim"
  // False when the cameras' frames are not at their configured ground scale (simulated
  // frames that are images as they are): the weed model then takes each frame squeezed to its
  // own input size.
  bool frames_at_camera_scale = true;

  // A GNSS fix reaches the sprayer: a receiver, or another board's over the fleet.
  [[nodiscard]] bool has_gnss() const noexcept { return gnss != nullptr || gnss_from_fleet; }

  // Sim only: advances the simulated world that no device drives (the vehicle's speed).
  std::function<void(double t_s)> drive_world;
  // Sim only: "valves=0x0 pump=0" as the plant sees them (written at exit for the tests).
  std::function<std::string()> describe_outputs;
  // Sim only: the output's writes fail with -error from now on (0: they work again); count > 0:
  // only its next `count` writes fail (the return-valve DAC only).
  std::function<void(OutputRole, int error, int count)> fail_output_writes;
  // Sim only: "sprayed_l=<the plant's true volume through the nozzles>" (written at exit).
  std::function<std::string()> plant_truth;
  // Sim only: a device fault by name (see SimFault::device); false for an unknown one.
  std::function<bool(const std::string& fault)> device_fault;
  // Sim only: runs fn on the plant, advanced to now and locked (ground truth, fault injection).
  std::function<void(const std::function<void(sim::plant::HydraulicPlant&)>&)> with_plant;

  std::vector<std::shared_ptr<void>> owned;  // keeps the devices alive

  // Every output to its safe value: valves closed, pump off, return valve open, buzzer/LED off.
  // Each output is tried (its backend retries); returns -errno per output whose safe value
  // could not be written, 0 for the others (and for outputs not wired).
  SafeWriteErrors force_safe() noexcept;
  // One output only (the main loop retries a failed one while in Fault); 0 or -errno.
  int force_safe(OutputRole role) noexcept;
  // What each output drives, for messages ("" when not wired).
  std::array<std::string, kOutputRoleCount> output_devices() const;
  // Registers each output's one-syscall safe write for the fatal-exit handlers
  // (io/emergency_outputs.hpp); returns how many outputs have one (the simulation has none).
  std::size_t register_emergency_writes() const noexcept;
};

// The 4-20 mA pressure sensor and the return-valve drive chain as configured (both backends).
io::CurrentLoopSensorConfig pressure_sensor_config(const Config& config);
io::ValveDriveConfig valve_drive_config(const Config& config);
// The GNSS receiver when gnss.enabled: gpsd at gnss.host:gnss.port in both modes (a simulation
// feeds its gpsd from gpsfake, so the whole client path runs).
void add_gnss(Backends& b, const Config& config);
// The yaw-rate gyro when turn.yaw_source = "imu" (IIO, in both modes). Throws naming the
// device or file.
void add_yaw_sensor(Backends& b, const Config& config);

// One output whose safe value could not be written.
struct SafeWriteFailure {
  std::string message;     // "pump: line offset 4 on GPIO chip 'gpiochip0' is busy (used by ...)"
  bool line_busy = false;  // a line another request still holds: worth a retry
};

// For ExecStopPost (weedsprayd --safe-outputs), after the daemon has gone however it went
// (kill -9 included): requests every output line at its safe value and releases it (a Pi keeps
// driving a released line's last value), and writes the return-valve DAC's safe value. Each
// output is tried on its own; returns the number of failures, each described in `failures`.
int write_hw_safe_outputs(const Config& config, std::vector<SafeWriteFailure>& failures);

// Loads the output manifest weedsprayd wrote at its start, or `config_path` when there is none
// (backends/output_manifest.hpp; without the weed source check: no model, no vision library),
// then write_hw_safe_outputs(); each failure on stderr prefixed by `program`. Returns the exit
// status: 0 when every output took its safe value. weedsprayd --safe-outputs and
// weedspray-safe-outputs.
int write_safe_outputs(const std::filesystem::path& config_path,
                       const std::filesystem::path& manifest_path, const char* program);

Backends make_hw_backends(const Config& config);

// The board's pressure converters from [adc], [dac] and [analog_modbus]: IIO devices or Modbus
// RTU analog modules, with the signal conversions that go with them. The DAC starts at its safe
// value. Throws std::runtime_error naming the device.
struct PressureConverters {
  std::shared_ptr<io::AnalogInput> adc;
  std::shared_ptr<io::AnalogOutput> dac;
  io::CurrentLoopSensorConfig sensor{};
  io::ValveDriveConfig drive{};
};
PressureConverters make_hw_pressure_converters(const Config& config, const io::Clock& clock);
// The return-valve DAC alone, written at its safe value (fully open) when it is made: the safe
// writers need no working ADC to open the relief path.
std::shared_ptr<io::AnalogOutput> make_hw_return_valve(const Config& config);
Backends make_sim_backends(const Config& config, const Options& options);

}  // namespace weedspray::daemon
