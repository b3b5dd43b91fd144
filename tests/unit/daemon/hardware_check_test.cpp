// SPDX-License-Identifier: Apache-2.0
// weedsprayd --check-config --hardware: every key hardware mode needs and every device the
// configuration names, checked against a test's /dev and /sys trees.
#include "daemon/config/hardware_check.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

namespace weedspray::daemon {
namespace {

namespace fs = std::filesystem;

class HardwareCheck : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("weedspray-hw-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
             "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(roots().dev);
    fs::create_directories(roots().sys);
  }
  void TearDown() override { fs::remove_all(root_); }

  DeviceRoots roots() const { return {root_ / "dev", root_ / "sys"}; }
  void make(const fs::path& relative) {
    fs::create_directories((root_ / relative).parent_path());
    std::ofstream(root_ / relative) << "x\n";
  }
  static std::set<std::string> keys(const std::vector<ConfigError>& problems) {
    std::set<std::string> named;
    for (const auto& problem : problems) named.insert(problem.key());
    return named;
  }

  fs::path root_;
};

TEST_F(HardwareCheck, TheShippedConfigNamesEveryMissingKeyAndDeviceAtItsLine) {
  const Config config = load_config(fs::path(WEEDSPRAY_SOURCE_DIR) / "etc" / "weedspray.toml");
  const std::vector<ConfigError> problems = check_hardware(config, roots());
  EXPECT_EQ(keys(problems),
            (std::set<std::string>{"gpio.valve_offsets", "gpio.heartbeat_offset",
                                   "gpio.estop_offset", "gpio.wheel_offset", "gpio.chip",
                                   "camera[0].device", "adc.iio_device", "dac.iio_device"}));
  for (const auto& problem : problems) {
    EXPECT_TRUE(problem.file().ends_with("weedspray.toml")) << problem.what();
    EXPECT_GT(problem.line(), 0) << problem.what();
  }
}

constexpr const char* kWired =
    "[gpio]\nchip = \"gpiochip2\"\nvalve_offsets = [1, 2, 3, 4]\nheartbeat_offset = 9\n"
    "estop_offset = 10\n"
    "wheel_offset = 7\n"
    "[[camera]]\ndevice = \"/dev/video3\"\n"
    "[adc]\niio_device = \"iio:device4\"\n"
    "[dac]\niio_device = \"iio:device5\"\n";

TEST_F(HardwareCheck, AWiredMachineWithItsDevicesPresentPasses) {
  for (const char* device : {"dev/gpiochip2", "dev/video3", "sys/bus/iio/devices/iio:device4",
                             "sys/bus/iio/devices/iio:device5"}) {
    make(device);
  }
  const Config config = load_config_from_strings({{"machine.toml", kWired}});
  const std::vector<ConfigError> problems = check_hardware(config, roots());
  EXPECT_TRUE(problems.empty()) << problems.front().what();
}

TEST_F(HardwareCheck, EachMissingDeviceIsNamedWithItsPath) {
  make("dev/gpiochip2");
  const Config config = load_config_from_strings(
      {{"machine.toml", std::string(kWired) +
                            "[modbus]\nenabled = true\ndevice = \"/dev/ttyUSB7\"\n"
                            "[flow]\ncounter = \"flow-counter\"\n"}});
  const std::vector<ConfigError> problems = check_hardware(config, roots());
  EXPECT_EQ(keys(problems),
            (std::set<std::string>{"camera[0].device", "adc.iio_device", "dac.iio_device",
                                   "modbus.device", "flow.counter"}));
  const auto modbus = std::find_if(problems.begin(), problems.end(),
                                   [](const auto& p) { return p.key() == "modbus.device"; });
  ASSERT_NE(modbus, problems.end());
  EXPECT_NE(std::string(modbus->what()).find("machine.toml:"), std::string::npos);
  EXPECT_NE(std::string(modbus->what()).find("/dev/ttyUSB7"), std::string::npos);
}

TEST_F(HardwareCheck, ACounterIsFoundByItsNameAndTheOptOutStandsForTheHeartbeat) {
  for (const char* device : {"dev/gpiochip2", "dev/video3", "sys/bus/iio/devices/iio:device4",
                             "sys/bus/iio/devices/iio:device5"}) {
    make(device);
  }
  fs::create_directories(root_ / "sys/bus/counter/devices/counter0");
  std::ofstream(root_ / "sys/bus/counter/devices/counter0/name") << "flow-counter\n";
  std::string text = kWired;
  text.replace(text.find("heartbeat_offset = 9\n"), 21, "heartbeat_opt_out = true\n");
  const Config config =
      load_config_from_strings({{"machine.toml", text + "[flow]\ncounter = \"flow-counter\"\n"}});
  const std::vector<ConfigError> problems = check_hardware(config, roots());
  EXPECT_TRUE(problems.empty()) << problems.front().what();
}

TEST_F(HardwareCheck, TheExampleMachineConfigSetsEveryKeyHardwareModeNeeds) {
  const Config config =
      load_config(fs::path(WEEDSPRAY_SOURCE_DIR) / "etc/examples/pi4-boom-4-nozzles.toml");
  EXPECT_EQ(
      keys(check_hardware(config, roots())),
      (std::set<std::string>{"gpio.chip", "camera[0].device", "adc.iio_device", "dac.iio_device"}))
      << "with no devices only the devices are missing";
  for (const char* device : {"dev/gpiochip0", "dev/video0", "sys/bus/iio/devices/iio:device0",
                             "sys/bus/iio/devices/iio:device1"}) {
    make(device);
  }
  const std::vector<ConfigError> problems = check_hardware(config, roots());
  EXPECT_TRUE(problems.empty()) << problems.front().what();
}

}  // namespace
}  // namespace weedspray::daemon
