// SPDX-License-Identifier: Apache-2.0
// The pressure converters on their own thread (io::AnalogIoWorker): when the ADC hangs (an I2C
// bus stuck, a Modbus module gone silent) the pressure loop keeps its rhythm, sees the sample
// age, and makes the machine safe; when the ADC comes back, pressure control resumes.
#include <gtest/gtest.h>

#include <atomic>
#include <string>
#include <thread>

#include "daemon/backends/backends.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "tests/sim/daemon/run_until.hpp"
#include "tests/sim/daemon/spraying_machine.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

class HangableAdc final : public io::AnalogInput {
 public:
  explicit HangableAdc(io::AnalogInput& inner) : inner_(inner) {}
  io::AnalogSample read() noexcept override {
    while (hung.load()) std::this_thread::sleep_for(1ms);
    return inner_.read();
  }
  std::atomic<bool> hung{false};

 private:
  io::AnalogInput& inner_;
};

TEST(ConverterFault, HungPressureAdcStopsThePumpAndClosesTheValvesThenRecovers) {
  SprayingMachine m;
  HangableAdc adc(*m.backends.pressure_adc);
  m.backends.pressure_adc = &adc;
  m.start();
  Backends& backends = m.backends;
  Sprayer& sprayer = *m.sprayer;
  const Config& config = m.config;

  const auto at_setpoint = [&] {
    const PressureStatus p = sprayer.pressure();
    return p.pump_on && p.sensor_ok &&
           std::abs(p.pressure_mpa - config.pressure.setpoint_mpa) < 0.03;
  };
  ASSERT_TRUE(run_until(backends, at_setpoint, 5s)) << "pressure never reached the set-point";
  ASSERT_NE(backends.describe_outputs().find("pump=1"), std::string::npos);
  // Spraying: wait until some valve is open, so "valves closed" below is a change, not a given.
  ASSERT_TRUE(run_until(
      backends,
      [&] { return backends.describe_outputs().find("valves=0x0 ") == std::string::npos; }, 10s))
      << "no valve ever opened: " << backends.describe_outputs();

  adc.hung = true;
  const auto safe = [&] {
    const PressureStatus p = sprayer.pressure();
    return !p.pump_on && !p.sensor_ok && sprayer.control().inputs_stale &&
           backends.describe_outputs().find("pump=0") != std::string::npos &&
           backends.describe_outputs().find("valves=0x0 ") != std::string::npos;
  };
  // Stale after 3 loop periods (30 ms); the valves close at the PWM thread's next wake.
  EXPECT_TRUE(run_until(backends, safe, 300ms)) << backends.describe_outputs();
  const PressureStatus hung = sprayer.pressure();
  EXPECT_GT(hung.stale_samples, 0U);
  const std::uint64_t cycles_when_hung = hung.cycles;
  std::this_thread::sleep_for(100ms);
  EXPECT_GE(sprayer.pressure().cycles, cycles_when_hung + 5) << "the loop kept its rhythm";

  adc.hung = false;
  EXPECT_TRUE(run_until(backends, at_setpoint, 5s)) << "pressure control did not resume";
  EXPECT_GT(sprayer.analog_io().overruns, 0U) << "the hang shows as missed converter slots";
  sprayer.stop();
  EXPECT_NE(backends.describe_outputs().find("pump=0"), std::string::npos);
}

}  // namespace
}  // namespace weedspray::daemon
