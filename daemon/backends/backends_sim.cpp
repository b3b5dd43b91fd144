// SPDX-License-Identifier: Apache-2.0
// The simulated machine for `weedsprayd --sim`: the hydraulic plant behind the io adapters,
// recorded field images as the cameras, simulated time paced to real time.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "control/nozzle_scheduler.hpp"
#include "daemon/backends/backends.hpp"
#include "daemon/config/vision_config.hpp"
#include "daemon/sprayer/geometry.hpp"
#include "io/sim/manual_estop_input.hpp"
#include "io/sim/memory_output_bank.hpp"
#include "io/sim/paced_clock.hpp"
#include "io/sim/replay_camera.hpp"
#include "io/sim/simulated_machine.hpp"
#include "sim/plant/hydraulic_plant.hpp"
#include "sim/plant/machine_draw.hpp"

#ifndef WEEDSPRAY_DEFAULT_SIM_IMAGES
#define WEEDSPRAY_DEFAULT_SIM_IMAGES "/usr/share/weedspray/images"
#endif

namespace weedspray::daemon {

double sim_speed_m_per_s(const SimSection& sim, double t_s) {
  const double span = sim.speed_max_m_per_s - sim.speed_min_m_per_s;
  const double phase = std::fmod(t_s / sim.speed_period_s, 1.0);
  if (sim.speed_profile == "constant") return sim.speed_max_m_per_s;
  if (sim.speed_profile == "ramp") {  // triangle: min -> max -> min
    return sim.speed_min_m_per_s + span * (phase < 0.5 ? 2 * phase : 2 - 2 * phase);
  }
  return sim.speed_min_m_per_s + span * (0.5 - 0.5 * std::cos(2 * std::numbers::pi * phase));
}

namespace {

// One line saying which machine the simulation runs and what it is made of (its nozzles' true
// flow coefficients and valve timing): what a calibration should find, and how a drawn machine
// differs from the ideal bench.
std::string describe_sim_machine(const SimSection& sim, std::uint64_t plant_seed,
                                 const sim::plant::HydraulicPlant& plant) {
  const sim::plant::PlantParams& p = plant.params();
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(3);
  if (sim.machine == "drawn") {
    out << "drawn machine " << sim.machine_index << " of fleet " << sim.machine_seed;
  } else {
    out << "ideal bench";
  }
  out << " (plant seed " << plant_seed << "): pump " << p.pump.open_flow_l_per_min
      << " L/min open, " << p.pump.shutoff_pressure_mpa << " MPa shut-off, " << p.pump.supply_volts
      << " V supply; meter K error " << 100.0 * p.flow_meter.k_factor_error
      << " %; nozzle k (L/min/sqrt MPa)";
  for (int i = 0; i < plant.nozzle_count(); ++i) {
    out << " " << plant.nozzle_truth(i).k_l_per_min_sqrt_mpa;
  }
  out << "; valve open/close delays (ms)";
  for (int i = 0; i < plant.nozzle_count(); ++i) {
    const auto& truth = plant.nozzle_truth(i);
    out << " " << 1000.0 * truth.open_delay_s << "/" << 1000.0 * truth.close_delay_s;
  }
  return out.str();
}

}  // namespace

Backends make_sim_backends(const Config& config, const Options& options) {
  if (config.boom.nozzles > sim::plant::kMaxNozzles) {
    throw std::runtime_error(
        "--sim: the plant model has at most " + std::to_string(sim::plant::kMaxNozzles) +
        " nozzles (boom.nozzles = " + std::to_string(config.boom.nozzles) + ")");
  }
  Backends b;
  b.mode = "sim";
  auto clock = std::make_shared<io::sim::PacedClock>(1.0);
  b.clock = clock.get();
  b.owned.push_back(clock);

  // The machine: drawn from the realistic spreads, or the ideal bench; then what the
  // configuration says of the boom, the scales and the wheel, which the daemon's view of its
  // machine depends on.
  io::sim::SimulatedMachineConfig machine_config;
  machine_config.seed = static_cast<std::uint64_t>(config.sim.seed);
  if (config.sim.machine == "drawn") {
    const sim::plant::Machine drawn = sim::plant::draw_machine(
        static_cast<std::uint64_t>(config.sim.machine_seed), config.sim.machine_index);
    machine_config.plant = drawn.params;
    machine_config.seed = drawn.seed;
  }
  auto& plant = machine_config.plant;
  plant.nozzle_count = config.boom.nozzles;
  plant.wheel.nominal_pulses_per_m = config.wheel.pulses_per_metre;
  plant.wheel.slip = config.sim.wheel_slip_pct / 100.0;
  plant.flow_meter.nominal_pulses_per_l = config.flow.pulses_per_litre;
  plant.pressure_sensor.full_scale_mpa = config.pressure.sensor_max_mpa;
  plant.pressure_sensor.shunt_ohms = config.adc.shunt_ohms;
  plant.tank.capacity_l = 200.0;  // a field-sized tank so a long simulation does not run dry
  plant.tank.initial_level_l = 200.0;
  auto machine = std::make_shared<io::sim::SimulatedMachine>(machine_config, *clock);
  b.owned.push_back(machine);
  machine->with_plant([&](sim::plant::HydraulicPlant& p) {
    spdlog::info("sim: {}", describe_sim_machine(config.sim, machine_config.seed, p));
  });

  auto valves = std::make_shared<io::sim::SimulatedValveBank>(*machine);
  auto pump = std::make_shared<io::sim::SimulatedPumpRelay>(*machine);
  auto adc = std::make_shared<io::sim::SimulatedPressureAdc>(*machine, *clock);
  b.drive = valve_drive_config(config);
  auto dac = std::make_shared<io::sim::SimulatedReturnValveDac>(*machine, b.drive);
  auto flow = std::make_shared<io::sim::SimulatedPulseInput>(
      *machine, io::sim::SimulatedPulseSource::kFlowMeter);
  auto wheel = std::make_shared<io::sim::SimulatedPulseInput>(
      *machine, io::sim::SimulatedPulseSource::kWheel);
  auto tank = std::make_shared<io::sim::SimulatedTankLevel>(*machine, *clock);
  auto buzzer = std::make_shared<io::sim::MemoryOutputBank>(1, 0, *clock);
  auto led = std::make_shared<io::sim::MemoryOutputBank>(1, 0, *clock);
  // Keeps its last 4096 edges so tests can see the wave.
  auto heartbeat = std::make_shared<io::sim::MemoryOutputBank>(1, 0, *clock, 4096);
  // The simulated machine's E-stop circuit, closed: the estop_open fault opens it.
  auto estop = std::make_shared<io::sim::ManualEstopInput>(*clock);
  b.valves = valves.get();
  b.pump = pump.get();
  b.pressure_adc = adc.get();
  b.return_valve = dac.get();
  b.flow = flow.get();
  b.wheel = config.wheel.source == "fixed" ? nullptr : wheel.get();
  b.tank = tank.get();
  b.buzzer = buzzer.get();
  b.led = led.get();
  b.heartbeat = heartbeat.get();
  b.estop = estop.get();
  for (std::shared_ptr<void> p :
       {std::shared_ptr<void>(valves), std::shared_ptr<void>(pump), std::shared_ptr<void>(adc),
        std::shared_ptr<void>(dac), std::shared_ptr<void>(flow), std::shared_ptr<void>(wheel),
        std::shared_ptr<void>(tank), std::shared_ptr<void>(buzzer), std::shared_ptr<void>(led),
        std::shared_ptr<void>(heartbeat), std::shared_ptr<void>(estop)}) {
    b.owned.push_back(p);
  }
  b.sensor = pressure_sensor_config(config);

  // The vehicle: its speed follows the [sim] profile; cameras pace their frames by it.
  auto speed = std::make_shared<std::atomic<double>>(sim_speed_m_per_s(config.sim, 0.0));
  b.owned.push_back(speed);
  const SimSection sim = config.sim;
  b.drive_world = [machine, speed, sim](double t_s) {
    const double v = sim_speed_m_per_s(sim, t_s);
    speed->store(v);
    machine->with_plant([v](sim::plant::HydraulicPlant& p) { p.set_ground_speed(v); });
  };
  b.with_plant = [machine](const std::function<void(sim::plant::HydraulicPlant&)>& fn) {
    machine->with_plant(fn);
  };
  b.fail_output_writes = [machine, buzzer, led, heartbeat, dac](OutputRole role, int error,
                                                                int count) {
    switch (role) {
      case OutputRole::kValves:
        machine->fail_writes(io::sim::SimulatedMachine::Output::kValves, error);
        break;
      case OutputRole::kPump:
        machine->fail_writes(io::sim::SimulatedMachine::Output::kPump, error);
        break;
      case OutputRole::kBuzzer:
        buzzer->fail_writes(error);
        break;
      case OutputRole::kLed:
        led->fail_writes(error);
        break;
      case OutputRole::kHeartbeat:
        heartbeat->fail_writes(error);
        break;
      case OutputRole::kReturnValve:
        dac->fail_writes(error, count > 0 ? count : -1);
        break;
    }
  };
  const double nominal_ppl = config.flow.pulses_per_litre;
  b.plant_truth = [machine, nominal_ppl]() {
    double delivered = 0;
    double metered = 0;
    double meter_gain = 1;
    machine->with_plant([&](sim::plant::HydraulicPlant& p) {
      delivered = p.total_delivered_l();
      metered = static_cast<double>(p.flow_meter_pulses()) / nominal_ppl;
      meter_gain = p.true_meter_pulses_per_l() / nominal_ppl;
    });
    // The true volume, what the meter's pulses say at the configured pulses/L, and the meter's
    // real pulses/L over the configured one (its calibration error).
    char text[160];
    std::snprintf(text, sizeof text, "sprayed_l=%.6f\nmetered_l=%.6f\nmeter_gain=%.6f\n", delivered,
                  metered, meter_gain);
    return std::string(text);
  };
  b.describe_outputs = [machine]() {
    std::ostringstream out;
    out << "valves=0x" << std::hex << machine->valve_mask() << std::dec
        << " pump=" << (machine->pump_on() ? 1 : 0) << "\n";
    return out.str();
  };

  std::string images = options.sim_images.empty() ? config.sim.images_dir : options.sim_images;
  if (images.empty()) images = WEEDSPRAY_DEFAULT_SIM_IMAGES;
  std::vector<std::shared_ptr<io::sim::ReplayCamera>> replay_cameras;
  for (const auto& camera_config : config.cameras) {
    io::sim::ReplayCameraConfig replay;
    replay.source = images;
    replay.loop = true;
    const auto footprint = control::ground_footprint(camera_geometry(camera_config));
    // A frame every 80 % of a footprint: consecutive images overlap, as a streaming camera's
    // do, so speed changes between two frames leave no unseen ground.
    replay.footprint_length_m = 0.8 * (footprint.far_m - footprint.near_m);
    replay.ground_speed_m_per_s = [speed]() { return speed->load(); };
    if (config.sim.images_mm_per_px > 0.0) {
      replay.source_mm_per_px = config.sim.images_mm_per_px;
      replay.frame_mm_per_px = camera_ground_mm_per_px(camera_config);
      replay.frame_width = camera_config.width;
      replay.frame_height = camera_config.height;
    } else {
      b.frames_at_camera_scale = false;
    }
    auto camera = std::make_shared<io::sim::ReplayCamera>(replay, *clock);
    b.cameras.push_back(camera.get());
    b.owned.push_back(camera);
    replay_cameras.push_back(camera);
  }
  b.device_fault = [tank, replay_cameras, estop](const std::string& fault) {
    if (fault == "estop_open" || fault == "estop_closed") {
      estop->set_closed(fault == "estop_closed");
    } else if (fault == "tank_silent" || fault == "tank_ok") {
      tank->inject_timeouts(fault == "tank_silent" ? 1 << 30 : 0);
    } else if (fault == "camera_gone" || fault == "camera_back") {
      for (const auto& camera : replay_cameras) camera->set_unplugged(fault == "camera_gone");
    } else {
      return false;
    }
    return true;
  };
  add_gnss(b, config);
  // A gyro is read through IIO in both modes: a simulation on the bench can use the board's
  // real IMU (or a test's fake sysfs tree), there being no yaw in the hydraulic plant.
  add_yaw_sensor(b, config);
  return b;
}

}  // namespace weedspray::daemon
