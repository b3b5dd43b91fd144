// SPDX-License-Identifier: Apache-2.0
// The pressure loop's thread: the converters' sample in, control::PressureLoopStep, the pump
// relay and return-valve DAC out; and the valve thread's watch over it.
#include <algorithm>

#include "daemon/sprayer/loop_time.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "io/signal_conversion.hpp"

namespace weedspray::daemon {

using loop_time::from_seconds;
using loop_time::seconds;
using namespace std::chrono_literals;

void Sprayer::watch_pressure_loop(Nanos now) noexcept {
  PressureStatus pressure;
  if (!pressure_.try_read(pressure)) return;
  const bool stalled = pressure_watch_.stale(pressure.cycles, now);
  if (stalled && pressure.pump_on && !pump_forced_off_.load()) {
    // The pressure loop owns the pump, but it is not running: switch the pump off from here
    // (force_safe is a single ioctl, safe beside a writer stuck in the kernel).
    if (io_.pump != nullptr) io_.pump->force_safe();
    pump_forced_off_.store(true);
    pressure_loop_stalls_.fetch_add(1, std::memory_order_relaxed);
  }
}

Nanos Sprayer::pressure_period() const noexcept {
  return from_seconds(1.0 / config_.pressure.loop_hz);
}

void Sprayer::pressure_loop(std::stop_token stop, Nanos first_deadline) noexcept {
  const Nanos period = pressure_period();
  // Two missed converter reads are tolerated; a third (a hung I2C read, a silent Modbus
  // module) makes the sample stale: sensor fault, pump off, return valve open.
  const Nanos max_sample_age = 3 * period;
  // A miss here is a whole period lost: the controller skipped a sample.
  io::PeriodicLoop loop(*io_.clock, period, first_deadline, &timing_.pressure_loop, period);
  io::AnalogSample sample;  // the newest copy obtained; kept when the slot is busy
  LiveParams params = params_.read();
  std::uint64_t params_version = params_.version();
  PressureStatus status;
  bool outputs_safe = false;
  io::LoopWatch valve_thread(kCrossWatchTimeout);
  bool valves_stalled = false;
  while (!stop.stop_requested()) {
    loop.wait_next();
    // The valve thread switched the pump off while this loop was stalled: the pump state this
    // loop believes in is gone, so decide it afresh.
    if (pump_forced_off_.exchange(false)) {
      status.pump_on = false;
      outputs_safe = false;
    }
    io::ValvePwmStats valves;
    if (pwm_driver_->try_stats(valves)) {
      const bool stalled = valve_thread.stale(valves.wakes, io_.clock->now());
      if (stalled && !valves_stalled) ++status.valve_thread_stalls;
      valves_stalled = stalled;
    }
    if (params_.version() != params_version) {
      params_version = params_.version();
      params_.try_read(params);
    }
    analog_io_->try_latest_sample(sample);
    const bool fresh =
        io::AnalogIoWorker::sample_is_fresh(sample, io_.clock->now(), max_sample_age);
    if (sample.ok && !fresh) ++status.stale_samples;
    const io::PressureReading reading = io::pressure_from_sensor_volts(sample.volts, io_.sensor);
    status.time = sample.time;
    status.current_ma = reading.current_ma;
    status.sensor_ok = fresh && reading.ok();
    status.pressure_mpa = status.sensor_ok ? reading.pressure_mpa : 0.0;
    status.adc_errors = sample.error_count;
    control::PressureLoopInputs in;
    in.pressure_mpa = reading.pressure_mpa;
    in.sensor_ok = status.sensor_ok;
    in.setpoint_mpa = params.setpoint_mpa;
    in.over_pressure_mpa = params.over_pressure_mpa;
    in.pump_enabled = params.pump_enabled;
    in.trip_reset = params.trip_reset;
    in.valves_stalled = valves_stalled;
    in.estop_held = estop_->held().load();
    const control::PressureLoopOutputs& out = pressure_step_->step(in);
    status.tripped = out.tripped;
    // A reading that is no pressure (a cut wire, a stale sample) or a trip closes the valves from
    // this loop in this cycle too, not through the control loop's next command and the valve
    // thread's next edge: the flag first (the valve thread holds them closed from its next
    // wake, and undoes a write that raced it), then the safe write itself.
    hold_valves_for_pressure(out.hold_valves, status);
    if (out.run) {
      // A refused write leaves the pump as it was: counted (output_write_failed), and tried
      // again next cycle.
      if (io_.pump != nullptr && !status.pump_on && io_.pump->write(1) != 0) {
        ++status.pump_write_errors;
        pwm_driver_->stop_heartbeat();
      } else {
        status.pump_on = true;
      }
      // An emergency stop that came while the pump was being switched on: its safe write may
      // have landed first. Off again at once; the next cycle takes the safe branch.
      if (estop_->held().load() && io_.pump != nullptr) {
        io_.pump->force_safe();
        status.pump_on = false;
      }
      outputs_safe = false;
      status.closure = out.closure;
      analog_io_->command(io::dac_volts_from_valve_opening(1.0 - status.closure, io_.drive));
    } else if (!outputs_safe) {
      // A stalled valve thread may hold valves open or shut: no pump, return valve open. A
      // latched emergency stop likewise (its reaction has already switched the pump off). A
      // refused safe write is counted and tried again next cycle (outputs_safe stays false).
      const bool pump_safe = io_.pump == nullptr || io_.pump->force_safe() == 0;
      if (!pump_safe) {
        ++status.pump_write_errors;
        pwm_driver_->stop_heartbeat();  // the pump may still run: the relay cuts it
      }
      analog_io_->command_safe();
      status.pump_on = false;
      status.closure = 0.0;
      outputs_safe = pump_safe;
    }
    status.cycles = loop.cycles();
    status.overruns = loop.overruns();
    status.misses = loop.misses();
    pressure_.publish(status);
  }
  if (io_.pump != nullptr) io_.pump->force_safe();
  analog_io_->command_safe();
}

void Sprayer::hold_valves_for_pressure(bool fault, PressureStatus& status) noexcept {
  if (fault == valves_held_by_pressure_.load(std::memory_order_relaxed)) return;
  valves_held_by_pressure_.store(fault);
  if (!fault) return;
  ++status.valve_holds;
  if (io_.valves != nullptr && io_.valves->force_safe() != 0) {
    ++status.valve_safe_write_errors;
    pwm_driver_->stop_heartbeat();  // a valve may stay open: the relay cuts them
  }
  status.valves_held_at = io_.clock->now();
}

// Nozzle health's share of the control loop: the valves' open times and the meter's pulses

}  // namespace weedspray::daemon
