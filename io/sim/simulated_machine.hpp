// SPDX-License-Identifier: Apache-2.0
// The simulated machine: owns a weedspray::sim::plant::HydraulicPlant and steps it up to the
// injected clock's time whenever any simulated device touches it (so it follows a ManualClock as
// fast as the loops run, or a PacedClock in real time). The device adapters below expose it through
// the io interfaces, exactly as the Linux backends expose the real machine.
//
// Sim only: a priority-inheriting mutex serialises the plant between the loops' threads and the
// main thread that drives the world; real-time guarantees are not a goal here, but a loop is
// never left waiting behind a preempted normal-priority holder.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>

#include "io/analog.hpp"
#include "io/clock.hpp"
#include "io/digital_output.hpp"
#include "io/pulse_input.hpp"
#include "io/signal_conversion.hpp"
#include "io/sim/priority_inheriting_mutex.hpp"
#include "io/tank_level.hpp"
#include "sim/plant/hydraulic_plant.hpp"

namespace weedspray::io::sim {

struct SimulatedMachineConfig {
  weedspray::sim::plant::PlantParams plant;
  std::uint64_t seed = 1;
  // Longest plant step per chunk; pulse edges are timestamped at chunk ends.
  std::chrono::nanoseconds max_chunk = std::chrono::microseconds(500);
};

class SimulatedMachine {
 public:
  SimulatedMachine(const SimulatedMachineConfig& config, const Clock& clock);

  // Steps the plant to the clock's current time (no-op if already there).
  void advance() noexcept;

  // Runs `fn(plant)` with the plant advanced to now and locked (tests, fault injection, speed).
  void with_plant(const std::function<void(weedspray::sim::plant::HydraulicPlant&)>& fn);

  // --- used by the adapters; each advances first ---
  void set_valves(std::uint32_t mask) noexcept;
  void set_pump(bool on) noexcept;
  void set_return_valve_volts(double volts) noexcept;
  double pressure_sensor_volts() noexcept;
  PulseSnapshot flow_pulses() noexcept;
  PulseSnapshot wheel_pulses() noexcept;
  double tank_level_pct() noexcept;
  int nozzle_count() const noexcept { return nozzle_count_; }
  std::uint32_t valve_mask() const noexcept;
  bool pump_on() const noexcept;

  std::chrono::nanoseconds plant_time() const noexcept;

  // Fault injection: writes to the valve bank or the pump relay fail with -error and leave the
  // plant's valves/pump as they were (a refused GPIO ioctl); 0 makes them work again.
  enum class Output { kValves, kPump };
  void fail_writes(Output output, int error) noexcept;
  int write_error(Output output) const noexcept;

 private:
  void advance_locked() noexcept;

  const Clock& clock_;
  std::chrono::nanoseconds max_chunk_;
  int nozzle_count_;
  mutable PriorityInheritingMutex mutex_;
  weedspray::sim::plant::HydraulicPlant plant_;
  std::chrono::nanoseconds start_;
  std::chrono::nanoseconds plant_time_;
  std::uint32_t valve_mask_ = 0;
  bool pump_on_ = false;
  std::atomic<int> valve_write_error_{0};
  std::atomic<int> pump_write_error_{0};
  PulseSnapshot flow_{};
  PulseSnapshot wheel_{};
};

// Nozzle valves -> plant valves. Safe = all closed.
class SimulatedValveBank final : public DigitalOutputBank {
 public:
  explicit SimulatedValveBank(SimulatedMachine& machine) noexcept : machine_(machine) {}
  std::size_t size() const noexcept override;
  int write(std::uint32_t mask) noexcept override;
  int force_safe() noexcept override;
  std::uint32_t safe_mask() const noexcept override { return 0; }
  std::string describe() const override { return "simulated valve bank"; }
  // What the plant's valves are commanded to now: a test checks it is 0 at the end.
  std::uint32_t mask() const noexcept { return machine_.valve_mask(); }

 private:
  SimulatedMachine& machine_;
};

// Pump relay (one line) -> plant pump. Safe = off.
class SimulatedPumpRelay final : public DigitalOutputBank {
 public:
  explicit SimulatedPumpRelay(SimulatedMachine& machine) noexcept : machine_(machine) {}
  std::size_t size() const noexcept override { return 1; }
  int write(std::uint32_t mask) noexcept override;
  int force_safe() noexcept override;
  std::uint32_t safe_mask() const noexcept override { return 0; }
  std::string describe() const override { return "simulated pump relay"; }

 private:
  SimulatedMachine& machine_;
};

enum class SimulatedPulseSource { kFlowMeter, kWheel };

class SimulatedPulseInput final : public PulseInput {
 public:
  SimulatedPulseInput(SimulatedMachine& machine, SimulatedPulseSource source) noexcept
      : machine_(machine), source_(source) {}
  PulseSnapshot snapshot() const noexcept override;

 private:
  SimulatedMachine& machine_;
  SimulatedPulseSource source_;
};

// ADC pin of the pressure sensor's I/V stage.
class SimulatedPressureAdc final : public AnalogInput {
 public:
  SimulatedPressureAdc(SimulatedMachine& machine, const Clock& clock) noexcept
      : machine_(machine), clock_(clock) {}
  AnalogSample read() noexcept override;

 private:
  SimulatedMachine& machine_;
  const Clock& clock_;
};

// DAC -> amplifier -> return valve volts. Safe: return valve fully open (no line pressure).
class SimulatedReturnValveDac final : public AnalogOutput {
 public:
  SimulatedReturnValveDac(SimulatedMachine& machine, const ValveDriveConfig& drive) noexcept;
  int write(double volts) noexcept override;
  int force_safe() noexcept override;
  double full_scale_volts() const noexcept override { return drive_.dac_full_scale_volts; }
  std::uint64_t error_count() const noexcept override { return errors_.load(); }
  double last_volts() const noexcept { return last_volts_; }
  // Fault injection (any thread): the next `count` writes fail with -error (a Modbus module that
  // does not answer) and leave the valve as it was; count < 0: every write until error is 0.
  void fail_writes(int error, int count) noexcept;

 private:
  SimulatedMachine& machine_;
  ValveDriveConfig drive_;
  double last_volts_ = 0.0;
  std::atomic<int> error_{0};
  std::atomic<int> failures_left_{0};
  std::atomic<std::uint64_t> errors_{0};
};

// Tank level from the plant's tank (drains as the pump delivers), with optional injected
// failures for alarm tests.
class SimulatedTankLevel final : public TankLevelSensor {
 public:
  SimulatedTankLevel(SimulatedMachine& machine, const Clock& clock) noexcept
      : machine_(machine), clock_(clock) {}
  TankLevelSample read() noexcept override;
  // The next `n` reads time out (any thread).
  void inject_timeouts(int n) noexcept { pending_timeouts_.store(n); }

 private:
  SimulatedMachine& machine_;
  const Clock& clock_;
  TankLevelSample counters_;
  std::atomic<int> pending_timeouts_{0};
};

}  // namespace weedspray::io::sim
