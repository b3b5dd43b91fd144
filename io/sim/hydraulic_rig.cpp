// SPDX-License-Identifier: Apache-2.0
#include "io/sim/hydraulic_rig.hpp"

#include <algorithm>
#include <mutex>

namespace weedspray::io::sim {

using std::chrono::nanoseconds;

HydraulicRig::HydraulicRig(const RigConfig& config, const Clock& clock)
    : clock_(clock),
      max_chunk_(config.max_chunk),
      nozzle_count_(config.plant.nozzle_count),
      plant_(config.plant, config.seed),
      start_(clock.now()),
      plant_time_(start_) {}

void HydraulicRig::advance_locked() noexcept {
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

void HydraulicRig::advance() noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
}

void HydraulicRig::with_plant(
    const std::function<void(weedspray::sim::plant::HydraulicPlant&)>& fn) {
  std::lock_guard lock(mutex_);
  advance_locked();
  fn(plant_);
}

void HydraulicRig::set_valves(std::uint32_t mask) noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  valve_mask_ = mask;
  plant_.set_valves(mask);
}

void HydraulicRig::set_pump(bool on) noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  pump_on_ = on;
  plant_.set_pump(on);
}

void HydraulicRig::set_return_valve_volts(double volts) noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  plant_.set_return_valve_volts(volts);
}

double HydraulicRig::pressure_sensor_volts() noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  return plant_.pressure_sensor_volts();
}

PulseSnapshot HydraulicRig::flow_pulses() noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  return flow_;
}

PulseSnapshot HydraulicRig::wheel_pulses() noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  return wheel_;
}

double HydraulicRig::tank_level_pct() noexcept {
  std::lock_guard lock(mutex_);
  advance_locked();
  return 100.0 * plant_.tank_level_l() / plant_.params().tank.capacity_l;
}

std::uint32_t HydraulicRig::valve_mask() const noexcept {
  std::lock_guard lock(mutex_);
  return valve_mask_;
}

bool HydraulicRig::pump_on() const noexcept {
  std::lock_guard lock(mutex_);
  return pump_on_;
}

nanoseconds HydraulicRig::plant_time() const noexcept {
  std::lock_guard lock(mutex_);
  return plant_time_;
}

void HydraulicRig::fail_writes(Output output, int error) noexcept {
  (output == Output::kValves ? valve_write_error_ : pump_write_error_).store(error);
}

int HydraulicRig::write_error(Output output) const noexcept {
  return (output == Output::kValves ? valve_write_error_ : pump_write_error_).load();
}

std::size_t RigValveBank::size() const noexcept {
  return static_cast<std::size_t>(rig_.nozzle_count());
}

int RigValveBank::write(std::uint32_t mask) noexcept {
  if (const int error = rig_.write_error(HydraulicRig::Output::kValves)) return -error;
  const std::uint32_t used = (1U << rig_.nozzle_count()) - 1U;
  rig_.set_valves(mask & used);
  return 0;
}

int RigValveBank::force_safe() noexcept {
  return write(0);
}

int RigPumpRelay::write(std::uint32_t mask) noexcept {
  if (const int error = rig_.write_error(HydraulicRig::Output::kPump)) return -error;
  rig_.set_pump((mask & 1U) != 0);
  return 0;
}

int RigPumpRelay::force_safe() noexcept {
  return write(0);
}

PulseSnapshot RigPulseInput::snapshot() const noexcept {
  return source_ == RigPulseSource::kFlowMeter ? rig_.flow_pulses() : rig_.wheel_pulses();
}

AnalogSample RigPressureAdc::read() noexcept {
  AnalogSample s;
  s.volts = rig_.pressure_sensor_volts();
  s.time = clock_.now();
  s.ok = true;
  return s;
}

RigReturnValveDac::RigReturnValveDac(HydraulicRig& rig, const ValveDriveConfig& drive) noexcept
    : rig_(rig), drive_(drive) {}

void RigReturnValveDac::fail_writes(int error, int count) noexcept {
  failures_left_.store(error != 0 ? count : 0);
  error_.store(error);
}

int RigReturnValveDac::write(double volts) noexcept {
  if (const int error = error_.load()) {
    const int left = failures_left_.load();
    if (left > 0 && failures_left_.fetch_sub(1) == 1) error_.store(0);  // the last one
    if (left != 0) {
      errors_.fetch_add(1);
      return -error;
    }
  }
  last_volts_ = std::clamp(volts, 0.0, drive_.dac_full_scale_volts);
  // The simulated valve acts as configured: the rig takes the control volts of a valve that
  // opens with them.
  rig_.set_return_valve_volts(valve_opening_from_dac_volts(last_volts_, drive_) *
                              drive_.valve_full_scale_volts);
  return 0;
}

int RigReturnValveDac::force_safe() noexcept {
  return write(dac_volts_from_valve_opening(1.0, drive_));
}

TankLevelSample RigTankLevel::read() noexcept {
  ++counters_.reads;
  counters_.time = clock_.now();
  if (pending_timeouts_ > 0) {
    --pending_timeouts_;
    ++counters_.timeouts;
    counters_.ok = false;
    return counters_;
  }
  counters_.level_pct = rig_.tank_level_pct();
  counters_.ok = true;
  return counters_;
}

}  // namespace weedspray::io::sim
