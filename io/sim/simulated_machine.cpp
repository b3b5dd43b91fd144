// SPDX-License-Identifier: Apache-2.0
#include "io/sim/simulated_machine.hpp"

#include <algorithm>
#include <mutex>

namespace weedspray::io::sim {

using std::chrono::nanoseconds;

SimulatedMachine::SimulatedMachine(const SimulatedMachineConfig& config, const Clock& clock)
    : clock_(clock),
      max_chunk_(config.max_chunk),
      nozzle_count_(config.plant.nozzle_count),
      plant_(config.plant, config.seed),
      start_(clock.now()),
      plant_time_(start_) {}

void SimulatedMachine::advance_locked() noexcept {
  const nanoseconds target = clock_.now();
  while (plant_time_ < target) {
    const nanoseconds chunk = std::min(max_chunk_, target - plant_time_);
    plant_.step(std::chrono::duration<double>(chunk).count());
    plant_time_ += chunk;
    const std::uint64_t flow = plant_.flow_meter_pulses();
    if (flow != flow_.count) {
      flow_.count = flow;
      flow_.last_edge_time = plant_time_;
    }
    const std::uint64_t wheel = plant_.wheel_pulses();
    if (wheel != wheel_.count) {
      wheel_.count = wheel;
      wheel_.last_edge_time = plant_time_;
    }
  }
}

void SimulatedMachine::advance() noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
}

void SimulatedMachine::with_plant(
    const std::function<void(weedspray::sim::plant::HydraulicPlant&)>& fn) {
  std::lock_guard lock(mutex_);
  advance_locked();
  fn(plant_);
}

void SimulatedMachine::set_valves(std::uint32_t mask) noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  valve_mask_ = mask;
  plant_.set_valves(mask);
}

void SimulatedMachine::set_pump(bool on) noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  pump_on_ = on;
  plant_.set_pump(on);
}

void SimulatedMachine::set_return_valve_volts(double volts) noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  plant_.set_return_valve_volts(volts);
}

double SimulatedMachine::pressure_sensor_volts() noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  return plant_.pressure_sensor_volts();
}

PulseSnapshot SimulatedMachine::flow_pulses() noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  return flow_;
}

PulseSnapshot SimulatedMachine::wheel_pulses() noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  return wheel_;
}

double SimulatedMachine::tank_level_pct() noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  return 100.0 * plant_.tank_level_l() / plant_.params().tank.capacity_l;
}

std::uint32_t SimulatedMachine::valve_mask() const noexcept {
  std::lock_guard lock(mutex_);
  return valve_mask_;
}

bool SimulatedMachine::pump_on() const noexcept {
  std::lock_guard lock(mutex_);
  return pump_on_;
}

nanoseconds SimulatedMachine::plant_time() const noexcept {
  std::lock_guard lock(mutex_);
  return plant_time_;
}

void SimulatedMachine::fail_writes(Output output, int error) noexcept {
  (output == Output::kValves ? valve_write_error_ : pump_write_error_).store(error);
}

int SimulatedMachine::write_error(Output output) const noexcept {
  return (output == Output::kValves ? valve_write_error_ : pump_write_error_).load();
}

std::size_t SimulatedValveBank::size() const noexcept {
  return static_cast<std::size_t>(machine_.nozzle_count());
}

int SimulatedValveBank::write(std::uint32_t mask) noexcept {
  if (const int error = machine_.write_error(SimulatedMachine::Output::kValves)) return -error;
  const std::uint32_t used = (1U << machine_.nozzle_count()) - 1U;
  machine_.set_valves(mask & used);
  return 0;
}

int SimulatedValveBank::force_safe() noexcept {
  return write(0);
}

int SimulatedPumpRelay::write(std::uint32_t mask) noexcept {
  if (const int error = machine_.write_error(SimulatedMachine::Output::kPump)) return -error;
  machine_.set_pump((mask & 1U) != 0);
  return 0;
}

int SimulatedPumpRelay::force_safe() noexcept {
  return write(0);
}

PulseSnapshot SimulatedPulseInput::snapshot() const noexcept {
  return source_ == SimulatedPulseSource::kFlowMeter ? machine_.flow_pulses()
                                                     : machine_.wheel_pulses();
}

AnalogSample SimulatedPressureAdc::read() noexcept {
  AnalogSample s;
  s.volts = machine_.pressure_sensor_volts();
  s.time = clock_.now();
  s.ok = true;
  return s;
}

SimulatedReturnValveDac::SimulatedReturnValveDac(SimulatedMachine& machine,
                                                 const ValveDriveConfig& drive) noexcept
    : machine_(machine), drive_(drive) {}

void SimulatedReturnValveDac::fail_writes(int error, int count) noexcept {
  failures_left_.store(error != 0 ? count : 0);
  error_.store(error);
}

int SimulatedReturnValveDac::write(double volts) noexcept {
  if (const int error = error_.load()) {
    const int left = failures_left_.load();
    if (left > 0 && failures_left_.fetch_sub(1) == 1) error_.store(0);  // the last one
    if (left != 0) {
      errors_.fetch_add(1);
      return -error;
    }
  }
  last_volts_ = std::clamp(volts, 0.0, drive_.dac_full_scale_volts);
  // The simulated valve acts as configured: the machine takes the control volts of a valve that
  // opens with them.
  machine_.set_return_valve_volts(valve_opening_from_dac_volts(last_volts_, drive_) *
                                  drive_.valve_full_scale_volts);
  return 0;
}

int SimulatedReturnValveDac::force_safe() noexcept {
  return write(dac_volts_from_valve_opening(1.0, drive_));
}

TankLevelSample SimulatedTankLevel::read() noexcept {
  ++counters_.reads;
  counters_.time = clock_.now();
  if (pending_timeouts_ > 0) {
    --pending_timeouts_;
    ++counters_.timeouts;
    counters_.ok = false;
    return counters_;
  }
  counters_.level_pct = machine_.tank_level_pct();
  counters_.ok = true;
  return counters_;
}

}  // namespace weedspray::io::sim
