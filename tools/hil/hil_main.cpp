// SPDX-License-Identifier: Apache-2.0
// weedspray-hil: the sprayer on the far side of the wires, for the hardware-in-the-loop scenario
// of the systemd guest (tests/vm-systemd/hil-scenario.sh). It runs the hydraulic plant model
// (sim/plant) in real time against the installed daemon, through kernel interfaces only:
//   - samples the valve, pump, buzzer, lamp and heartbeat lines in gpio-sim sysfs at --rate-hz
//     and drives the plant's solenoids and pump relay with what it reads; integrates each
//     valve's measured open time (its duty);
//   - makes the flow meter's and the wheel sensor's pulses with gpio-sim pulls, as many as the
//     plant's meter and wheel produce;
//   - writes the pressure transmitter's voltage into the board's IIO ADC input and reads the
//     return valve's control voltage from its IIO DAC output, every 4th sample (500 Hz at
//     2 kHz; iio_converters.hpp);
//   - serves the tank level as a Modbus RTU slave on a pty pair (modbus_slaves.hpp);
//   - with --camera-device, shows the daemon's camera field images: raw YUYV frames written
//     into v4l2loopback (loopback_camera.hpp).
// Interface for the scenario script, in --run-dir:
//   status   rewritten every 50 ms: key=value lines (cumulative counters and the plant's state)
//   control  a FIFO taking one command a line: "speed M_PER_S", "tank_l LITRES",
//            "sensor_wire cut|mended" (trace marker "sensor_cut", the pressure sensor's loop
//            current 0 mA at the ADC input, marker "sensor_cut_applied"), "frame NAME" (the
//            camera's frame NAME.yuyv
//            from now on), "quit"
// On quit (or SIGTERM) it prints its ground truth as "WEEDSPRAY-HIL-TRUTH key=value" lines.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "io/signal_conversion.hpp"
#include "sim/plant/hydraulic_plant.hpp"
#include "tools/hil/iio_converters.hpp"
#include "tools/hil/loopback_camera.hpp"
#include "tools/hil/modbus_slaves.hpp"
#include "tools/hil/sim_gpio_lines.hpp"

namespace weedspray::hil {
namespace {

std::atomic<bool> g_quit{false};

struct Options {
  std::string chip_dir;  // the gpio-sim chip with the daemon's lines
  std::vector<int> valve_lines;
  int pump_line = -1;
  int buzzer_line = -1;
  int lamp_line = -1;
  int heartbeat_line = -1;
  int wheel_line = -1;
  std::string flow_chip_dir;  // the flow meter's chip (interrupt-cnt), may be chip_dir
  int flow_line = -1;
  std::string run_dir = "/run/weedspray-hil";
  double rate_hz = 2000;
  double speed_m_per_s = 0;
  double tank_capacity_l = 200;
  double tank_level_l = 150;
  double wheel_pulses_per_m = 100;
  double flow_pulses_per_l = 8500;
  IioConvertersConfig iio;
  double tank_pct_per_count = 0.1;
  std::uint64_t seed = 1;
  LoopbackCameraConfig camera;  // no device: no camera
};

double now_s() {
  struct timespec ts {};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

std::uint16_t counts(double value, double per_count) {
  return static_cast<std::uint16_t>(std::clamp(std::lround(value / per_count), 0L, 65535L));
}

struct Lines {
  std::vector<std::unique_ptr<SimOutputLine>> valves;
  std::unique_ptr<SimOutputLine> pump, buzzer, lamp, heartbeat;
  std::unique_ptr<SimInputLine> flow, wheel;
};

std::unique_ptr<SimOutputLine> output_line(const std::string& dir, int offset) {
  return offset < 0 ? nullptr : std::make_unique<SimOutputLine>(dir, offset);
}

// What the sampler measured, cumulative since start.
struct Measured {
  std::uint64_t samples = 0;
  double sampled_s = 0;  // time covered by samples
  double max_gap_s = 0;  // longest interval between two samples
  std::vector<double> valve_open_s;
  std::uint64_t heartbeat_edges = 0;
  std::uint64_t flow_sent = 0;
  std::uint64_t wheel_sent = 0;
  bool pump = false, buzzer = false, lamp = false, heartbeat = false;
  std::uint32_t valve_mask = 0;
};

void write_status(const Options& o, const sim::plant::HydraulicPlant& plant, const Measured& m,
                  ModbusBoard& board, IioConverters& iio, const LoopbackCamera* camera,
                  double elapsed_s) {
  std::ostringstream s;
  s << "elapsed_s=" << elapsed_s << "\nsamples=" << m.samples << "\nsampled_s=" << m.sampled_s
    << "\nsample_hz=" << (m.sampled_s > 0 ? static_cast<double>(m.samples) / m.sampled_s : 0)
    << "\nmax_gap_ms=" << m.max_gap_s * 1e3 << "\npressure_mpa=" << plant.line_pressure_mpa()
    << "\npump=" << m.pump << "\nbuzzer=" << m.buzzer << "\nlamp=" << m.lamp
    << "\nvalve_mask=" << m.valve_mask << "\nheartbeat_edges=" << m.heartbeat_edges
    << "\nreturn_opening=" << plant.return_valve_opening()
    << "\nnozzle_flow_l_per_min=" << plant.total_nozzle_flow_l_per_min()
    << "\ntank_pct=" << plant.tank_level_l() / o.tank_capacity_l * 100
    << "\ndistance_m=" << plant.distance_m() << "\nflow_sent=" << m.flow_sent
    << "\nwheel_sent=" << m.wheel_sent
    << "\nflow_backlog=" << plant.flow_meter_pulses() - m.flow_sent
    << "\nwheel_backlog=" << plant.wheel_pulses() - m.wheel_sent;
  for (std::size_t i = 0; i < m.valve_open_s.size(); ++i)
    s << "\nvalve" << i << "_open_s=" << m.valve_open_s[i];
  s << "\ndac_volts=" << iio.dac_volts() << "\nadc_counts=" << iio.adc_counts()
    << "\nadc_writes=" << iio.adc_writes() << "\niio_errors=" << iio.errors();
  {
    std::lock_guard lock(board.mutex);
    s << "\ntank_requests=" << board.tank_requests;
  }
  if (camera)
    s << "\ncamera_frame=" << camera->current() << "\ncamera_writes=" << camera->writes()
      << "\ncamera_write_errors=" << camera->write_errors();
  s << "\n";
  const std::string tmp = o.run_dir + "/status.tmp";
  if (FILE* f = std::fopen(tmp.c_str(), "w")) {
    std::fputs(s.str().c_str(), f);
    std::fclose(f);
    std::rename(tmp.c_str(), (o.run_dir + "/status").c_str());
  }
}

void print_truth(const sim::plant::HydraulicPlant& plant, const Measured& m) {
  std::printf("WEEDSPRAY-HIL-TRUTH pressure_mpa=%.4f\n", plant.line_pressure_mpa());
  std::printf("WEEDSPRAY-HIL-TRUTH delivered_l=%.4f\n", plant.total_delivered_l());
  for (int i = 0; i < plant.nozzle_count(); ++i)
    std::printf("WEEDSPRAY-HIL-TRUTH nozzle%d_delivered_l=%.4f open_s=%.3f\n", i,
                plant.nozzle_delivered_l(i), m.valve_open_s[static_cast<std::size_t>(i)]);
  std::printf("WEEDSPRAY-HIL-TRUTH distance_m=%.3f\n", plant.distance_m());
  std::printf("WEEDSPRAY-HIL-TRUTH tank_l=%.3f\n", plant.tank_level_l());
  std::printf("WEEDSPRAY-HIL-TRUTH flow_pulses=%llu of %llu wheel_pulses=%llu of %llu\n",
              static_cast<unsigned long long>(m.flow_sent),
              static_cast<unsigned long long>(plant.flow_meter_pulses()),
              static_cast<unsigned long long>(m.wheel_sent),
              static_cast<unsigned long long>(plant.wheel_pulses()));
  std::printf("WEEDSPRAY-HIL-TRUTH samples=%llu sample_hz=%.0f max_gap_ms=%.2f\n",
              static_cast<unsigned long long>(m.samples),
              m.sampled_s > 0 ? static_cast<double>(m.samples) / m.sampled_s : 0.0,
              m.max_gap_s * 1e3);
  std::fflush(stdout);
}

// What a command acts on.
struct CommandTarget {
  const Options& options;
  sim::plant::HydraulicPlant& plant;
  IioConverters& iio;
  LoopbackCamera* camera;
};

// A line in the kernel's trace (tracefs trace_marker), so the scenario can time the daemon's
// reaction from the very moment the plant changed; nothing when tracing is not mounted. The
// file stays open (main opens it with the first marker): an open per marker would widen the
// gap between a change and its markers.
void trace_marker(const char* text) {
  static const int fd = ::open("/sys/kernel/tracing/trace_marker", O_WRONLY | O_CLOEXEC);
  if (fd < 0) return;
  [[maybe_unused]] const ssize_t n = ::write(fd, text, std::strlen(text));
}

void handle_command(const std::string& line, CommandTarget& target) {
  std::istringstream in(line);
  std::string verb, argument;
  in >> verb >> argument;
  const double value = std::strtod(argument.c_str(), nullptr);
  if (verb == "speed") target.plant.set_ground_speed(value);
  if (verb == "tank_l") target.plant.set_tank_level_l(value);
  if (verb == "sensor_wire" && (argument == "cut" || argument == "mended")) {
    // A marker, the ADC input at once (not at the next plant step), a second marker. The
    // daemon's real-time loops can act on the new input before this process writes another
    // line, so the scenario times from the first (an upper bound: it includes this write).
    const bool cut = argument == "cut";
    trace_marker(cut ? "sensor_cut" : "sensor_mended");
    target.plant.set_sensor_wire_broken(cut);
    target.iio.set_adc_volts(target.plant.pressure_sensor_volts());
    trace_marker(cut ? "sensor_cut_applied" : "sensor_mended_applied");
  }
  if (verb == "frame" && !(target.camera && target.camera->show(argument)))
    std::fprintf(stderr, "weedspray-hil: no camera frame '%s'\n", argument.c_str());
  if (verb == "quit") g_quit = true;
}

void poll_commands(int fifo, std::string& pending, CommandTarget& target) {
  char buffer[256];
  ssize_t n = 0;
  while ((n = ::read(fifo, buffer, sizeof buffer)) > 0) pending.append(buffer, n);
  std::size_t end = 0;
  while ((end = pending.find('\n')) != std::string::npos) {
    handle_command(pending.substr(0, end), target);
    pending.erase(0, end + 1);
  }
}

int run(const Options& o) {
  ::mkdir(o.run_dir.c_str(), 0755);
  trace_marker("weedspray-hil started");
  ModbusBoard board;
  sim::plant::PlantParams params;
  params.nozzle_count = static_cast<int>(o.valve_lines.size());
  params.wheel.nominal_pulses_per_m = o.wheel_pulses_per_m;
  params.flow_meter.nominal_pulses_per_l = o.flow_pulses_per_l;
  params.tank.capacity_l = o.tank_capacity_l;
  params.tank.initial_level_l = o.tank_level_l;
  sim::plant::HydraulicPlant plant(params, o.seed);
  plant.set_ground_speed(o.speed_m_per_s);

  Lines lines;
  for (int offset : o.valve_lines)
    lines.valves.push_back(std::make_unique<SimOutputLine>(o.chip_dir, offset));
  lines.pump = output_line(o.chip_dir, o.pump_line);
  lines.buzzer = output_line(o.chip_dir, o.buzzer_line);
  lines.lamp = output_line(o.chip_dir, o.lamp_line);
  lines.heartbeat = output_line(o.chip_dir, o.heartbeat_line);
  if (o.flow_line >= 0)
    lines.flow = std::make_unique<SimInputLine>(
        o.flow_chip_dir.empty() ? o.chip_dir : o.flow_chip_dir, o.flow_line);
  if (o.wheel_line >= 0) lines.wheel = std::make_unique<SimInputLine>(o.chip_dir, o.wheel_line);

  IioConverters iio(o.iio);
  iio.set_adc_volts(plant.pressure_sensor_volts());
  {
    std::lock_guard lock(board.mutex);
    board.tank_counts =
        counts(plant.tank_level_l() / o.tank_capacity_l * 100, o.tank_pct_per_count);
  }
  start_tank_bus({.link = o.run_dir + "/tank"}, board);
  std::unique_ptr<LoopbackCamera> camera;
  if (!o.camera.device.empty()) camera = std::make_unique<LoopbackCamera>(o.camera);
  const std::string fifo_path = o.run_dir + "/control";
  ::unlink(fifo_path.c_str());
  ::mkfifo(fifo_path.c_str(), 0600);
  const int fifo = ::open(fifo_path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);

  // The sampler stays at normal priority: on the emulated CPUs it is busy all the time, and as a
  // SCHED_FIFO thread it would starve the daemon's own threads and the kernel's IRQ threads
  // (priority 50, the wheel's edge events) - a machine must not slow down its controller. Its
  // achieved rate is reported (sample_hz). The Modbus thread answers at SCHED_FIFO 60.

  Measured m;
  m.valve_open_s.assign(lines.valves.size(), 0.0);
  const io::ValveDriveConfig drive;
  const double period_s = 1.0 / o.rate_hz;
  const double start = now_s();
  double last = start;
  double dac_volts = iio.dac_volts();
  double next_status = start;
  std::string pending;
  CommandTarget commands{o, plant, iio, camera.get()};
  struct timespec next {};
  clock_gettime(CLOCK_MONOTONIC, &next);
  std::printf("weedspray-hil: running (%zu valves, %.0f Hz sampling, status in %s)\n",
              lines.valves.size(), o.rate_hz, o.run_dir.c_str());
  std::fflush(stdout);
  while (!g_quit) {
    next.tv_nsec += static_cast<long>(period_s * 1e9);
    while (next.tv_nsec >= 1000000000L) {
      next.tv_nsec -= 1000000000L;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    const double t = now_s();
    const double dt = t - last;
    last = t;
    if (t - (static_cast<double>(next.tv_sec) + static_cast<double>(next.tv_nsec) * 1e-9) > 0.05)
      clock_gettime(CLOCK_MONOTONIC, &next);  // far behind (a stalled emulated CPU): no burst

    // Sample: each line's level held since the previous sample.
    std::uint32_t mask = 0;
    for (std::size_t i = 0; i < lines.valves.size(); ++i) {
      if (lines.valves[i]->high()) {
        mask |= 1U << i;
        m.valve_open_s[i] += dt;
      }
    }
    m.valve_mask = mask;
    m.pump = lines.pump && lines.pump->high();
    // The signalling lines change slowly (the heartbeat at up to 250 Hz): every 4th sample, so
    // the emulated CPU's time goes to the valves. So do the converters: the daemon reads the ADC
    // and writes the DAC at its pressure loop's 100 Hz, and at 2 kHz every 4th sample is 500 Hz,
    // an ADS1115 converting at 475 samples a second.
    const bool slow_slot = m.samples % 4 == 0;
    if (slow_slot) {
      m.buzzer = lines.buzzer && lines.buzzer->high();
      m.lamp = lines.lamp && lines.lamp->high();
      const bool heartbeat = lines.heartbeat && lines.heartbeat->high();
      if (heartbeat != m.heartbeat) ++m.heartbeat_edges;
      m.heartbeat = heartbeat;
    }
    ++m.samples;
    m.sampled_s += dt;
    m.max_gap_s = std::max(m.max_gap_s, dt);

    // The machine reacts.
    plant.set_valves(mask);
    plant.set_pump(m.pump);
    if (slow_slot) dac_volts = iio.dac_volts();
    plant.set_return_valve_volts(io::valve_volts_from_dac_volts(dac_volts, drive));
    plant.step(std::min(dt, 0.05));
    if (slow_slot) iio.set_adc_volts(plant.pressure_sensor_volts());
    {
      std::lock_guard lock(board.mutex);
      board.tank_counts =
          counts(plant.tank_level_l() / o.tank_capacity_l * 100, o.tank_pct_per_count);
    }
    // Its sensors pulse (at most one edge each per sample: half the sampling rate in pulses).
    if (lines.flow) {
      lines.flow->step(plant.flow_meter_pulses());
      m.flow_sent = lines.flow->sent();
    }
    if (lines.wheel) {
      lines.wheel->step(plant.wheel_pulses());
      m.wheel_sent = lines.wheel->sent();
    }

    if (t >= next_status) {
      next_status = t + 0.05;
      if (fifo >= 0) poll_commands(fifo, pending, commands);
      write_status(o, plant, m, board, iio, camera.get(), t - start);
    }
  }
  write_status(o, plant, m, board, iio, camera.get(), now_s() - start);
  print_truth(plant, m);
  return 0;
}

}  // namespace
}  // namespace weedspray::hil

int main(int argc, char** argv) {
  using weedspray::hil::Options;
  Options o;
  CLI::App app{"weedspray-hil: the simulated sprayer behind gpio-sim, IIO and a Modbus pty"};
  app.add_option("--chip-dir", o.chip_dir, "gpio-sim chip's sysfs dir (.../gpio-sim.N/gpiochipM)")
      ->required();
  app.add_option("--valve-lines", o.valve_lines, "offsets of the valve lines")->required();
  app.add_option("--pump-line", o.pump_line);
  app.add_option("--buzzer-line", o.buzzer_line);
  app.add_option("--lamp-line", o.lamp_line);
  app.add_option("--heartbeat-line", o.heartbeat_line);
  app.add_option("--wheel-line", o.wheel_line);
  app.add_option("--flow-chip-dir", o.flow_chip_dir, "the flow meter's chip (default: chip-dir)");
  app.add_option("--flow-line", o.flow_line);
  app.add_option("--run-dir", o.run_dir);
  app.add_option("--rate-hz", o.rate_hz, "line sampling and plant step rate");
  app.add_option("--speed", o.speed_m_per_s, "initial ground speed [m/s]");
  app.add_option("--tank-capacity-l", o.tank_capacity_l);
  app.add_option("--tank-level-l", o.tank_level_l);
  app.add_option("--wheel-pulses-per-m", o.wheel_pulses_per_m);
  app.add_option("--flow-pulses-per-l", o.flow_pulses_per_l, "the flow meter's label value");
  app.add_option("--iio-dir", o.iio.device_dir,
                 "the IIO device's sysfs dir: pressure into its ADC input, return valve from its "
                 "DAC output")
      ->required();
  app.add_option("--adc-channel", o.iio.adc_channel, "in_voltageN_raw of the pressure sensor");
  app.add_option("--dac-channel", o.iio.dac_channel, "out_voltageN_raw of the return valve");
  app.add_option("--adc-mv-per-count", o.iio.adc_mv_per_count,
                 "the daemon's adc.iio_scale_mv (0.125: an ADS1115 at +-4.096 V)");
  app.add_option("--adc-max-count", o.iio.adc_max_count, "the ADC's positive full scale");
  app.add_option("--dac-mv-per-count", o.iio.dac_mv_per_count, "the daemon's dac.iio_scale_mv");
  app.add_option("--seed", o.seed);
  app.add_option("--camera-device", o.camera.device, "v4l2loopback node to write frames into");
  app.add_option("--camera-frames", o.camera.frames_dir,
                 "folder of NAME.yuyv frames (weedspray-lab hil-frames)");
  app.add_option("--camera-frame", o.camera.first_frame, "the frame shown first")
      ->default_val("field");
  app.add_option("--camera-width", o.camera.width)->default_val(320);
  app.add_option("--camera-height", o.camera.height)->default_val(180);
  app.add_option("--camera-fps", o.camera.fps, "frames written per second")->default_val(2.0);
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGTERM, [](int) { weedspray::hil::g_quit = true; });
  std::signal(SIGINT, [](int) { weedspray::hil::g_quit = true; });
  try {
    return weedspray::hil::run(o);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "weedspray-hil: %s\n", error.what());
    return 1;
  }
}
