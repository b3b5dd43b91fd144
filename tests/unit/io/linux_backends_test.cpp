// SPDX-License-Identifier: Apache-2.0
// The Linux backends' start-up paths that need no hardware: IIO against a fake sysfs tree,
// and the clear errors for missing GPIO chips / cameras. The real-kernel paths (gpio-sim,
// vivid) run in the QEMU harness (tests/vm).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "io/linux/gpio_digital_input.hpp"
#include "io/linux/gpio_estop_input.hpp"
#include "io/linux/gpio_output_bank.hpp"
#include "io/linux/gpio_pulse_input.hpp"
#include "io/linux/iio_analog.hpp"
#include "io/linux/iio_gyro.hpp"
#include "io/linux/monotonic_clock.hpp"
#include "io/linux/v4l2_camera.hpp"

namespace weedspray::io::hw {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

class FakeIio : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/weedspray-iio-XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    root_ = tmpl;
    adc_ = root_ / "iio:device0";
    dac_ = root_ / "iio:device1";
    fs::create_directories(adc_);
    fs::create_directories(dac_);
    put(adc_ / "name", "ads1015");
    put(adc_ / "in_voltage0_raw", "1000");
    put(adc_ / "in_voltage_scale", "1.000000000");  // shared scale, mV per count
    put(adc_ / "in_voltage1_raw", "garbage");
    put(adc_ / "in_voltage1_scale", "0.5");
    put(dac_ / "name", "mcp4725");
    put(dac_ / "out_voltage0_raw", "0");
    put(dac_ / "out_voltage0_scale", "0.805664062");  // 3300 mV / 4096
  }
  void TearDown() override { fs::remove_all(root_); }
  static void put(const fs::path& p, const std::string& text) { std::ofstream(p) << text << "\n"; }
  static std::string get(const fs::path& p) {
    std::ifstream in(p);
    std::string s;
    std::getline(in, s);
    return s;
  }

  fs::path root_, adc_, dac_;
  MonotonicClock clock_;
};

TEST_F(FakeIio, ReadsVoltsFromRawAndScale) {
  IioAnalogInput adc({"iio:device0", 0, 0.0, root_.string()}, clock_);
  EXPECT_DOUBLE_EQ(adc.scale_mv(), 1.0);
  AnalogSample s = adc.read();
  EXPECT_TRUE(s.ok);
  EXPECT_DOUBLE_EQ(s.volts, 1.0);
  EXPECT_GT(s.time.count(), 0);
  put(adc_ / "in_voltage0_raw", "2500");
  s = adc.read();  // the fd stays open; each read re-reads from offset 0
  EXPECT_DOUBLE_EQ(s.volts, 2.5);
}

TEST_F(FakeIio, FindsTheDeviceByNameAndCountsBadReads) {
  IioAnalogInput adc({"ads1015", 1, 0.0, root_.string()}, clock_);
  EXPECT_DOUBLE_EQ(adc.scale_mv(), 0.5) << "the channel's own scale wins";
  const AnalogSample s = adc.read();
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.error_count, 1U);
}

TEST_F(FakeIio, DacWritesRawCountsAndStartsSafe) {
  {
    IioAnalogOutputConfig config{{"mcp4725", 0, 0.0, root_.string()}, 3.3, 3.3, 4095};
    IioAnalogOutput dac(config);
    EXPECT_EQ(get(dac_ / "out_voltage0_raw"), "4095") << "safe value, within 12 bits";
    EXPECT_EQ(dac.write(1.65), 0);
    EXPECT_EQ(std::stol(get(dac_ / "out_voltage0_raw")), 2048);
    EXPECT_EQ(dac.write(99.0), 0);
    EXPECT_EQ(std::stol(get(dac_ / "out_voltage0_raw")), 4095) << "clamped to full scale";
    dac.write(0.5);
  }
  EXPECT_EQ(std::stol(get(dac_ / "out_voltage0_raw")), 4095) << "destructor forces safe";
}

TEST_F(FakeIio, ClearErrorsNameTheDeviceOrFile) {
  try {
    IioAnalogInput adc({"ads9999", 0, 0.0, root_.string()}, clock_);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("ads9999"), std::string::npos) << e.what();
  }
  try {
    IioAnalogInput adc({"iio:device0", 5, 0.0, root_.string()}, clock_);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("in_voltage5_raw"), std::string::npos) << e.what();
  }
  try {
    IioAnalogInput adc({"iio:device1", 0, 0.0, root_.string()}, clock_);  // a DAC: no scale
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("scale"), std::string::npos) << e.what();
  }
}

// An MPU-6050 as inv_mpu6050 shows it: a shared rad/s scale (250 deg/s range: 1/131 deg/s per
// count), and a BMI160-like device with a per-axis scale and an offset.
TEST_F(FakeIio, GyroGivesTheYawRateClockwise) {
  const fs::path imu = root_ / "iio:device2";
  fs::create_directories(imu);
  put(imu / "name", "mpu6050");
  put(imu / "in_anglvel_scale", "0.000133090");  // rad/s per count
  put(imu / "in_anglvel_z_raw", "-1179");        // a right (clockwise) turn, z up
  IioGyro up({"mpu6050", 'z', true, root_.string()});
  YawRateSample s = up.read();
  ASSERT_TRUE(s.ok);
  EXPECT_NEAR(s.deg_per_s, 1179 * 0.000133090 * 180 / M_PI, 1e-9);  // +8.99 deg/s
  EXPECT_NEAR(s.deg_per_s, 8.99, 0.01);
  // Mounted upside down, the same reading is a left turn.
  IioGyro down({"mpu6050", 'z', false, root_.string()});
  EXPECT_NEAR(down.read().deg_per_s, -8.99, 0.01);
  // The file is re-read each time; a bad value is a failed sample, not a number.
  put(imu / "in_anglvel_z_raw", "0");
  EXPECT_DOUBLE_EQ(up.read().deg_per_s, 0.0);
  put(imu / "in_anglvel_z_raw", "oops");
  EXPECT_FALSE(up.read().ok);

  const fs::path bmi = root_ / "iio:device3";
  fs::create_directories(bmi);
  put(bmi / "name", "bmi160");
  put(bmi / "in_anglvel_x_scale", "0.001");
  put(bmi / "in_anglvel_x_offset", "-10");
  put(bmi / "in_anglvel_x_raw", "110");
  IioGyro x({"bmi160", 'x', true, root_.string()});
  EXPECT_NEAR(x.read().deg_per_s, -100 * 0.001 * 180 / M_PI, 1e-9);
}

TEST_F(FakeIio, GyroErrorsNameTheDeviceOrFile) {
  const fs::path imu = root_ / "iio:device2";
  fs::create_directories(imu);
  put(imu / "name", "mpu6050");
  put(imu / "in_anglvel_z_raw", "0");
  try {
    IioGyro gyro({"mpu6050", 'z', true, root_.string()});
    FAIL() << "no scale accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("in_anglvel_z_scale or in_anglvel_scale"),
              std::string::npos)
        << e.what();
  }
  put(imu / "in_anglvel_scale", "0.0001");
  EXPECT_THROW(IioGyro({"mpu6050", 'q', true, root_.string()}), std::runtime_error);
  try {
    IioGyro gyro({"mpu6050", 'y', true, root_.string()});
    FAIL() << "no y axis file accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("in_anglvel_y_raw"), std::string::npos) << e.what();
  }
  EXPECT_THROW(IioGyro({"bno055", 'z', true, root_.string()}), std::runtime_error);
}

TEST(GpioBackends, MissingChipOrLineIsAClearError) {
  GpioOutputBankConfig bank;
  bank.chip = "weedspray-no-such-chip";
  bank.lines = {{"", 0, false, false}};
  try {
    GpioOutputBank b(bank);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("weedspray-no-such-chip"), std::string::npos) << e.what();
  }
  GpioPulseInputConfig pulse;
  pulse.line.name = "weedspray-no-such-line";
  try {
    GpioPulseInput p(pulse);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("weedspray-no-such-line"), std::string::npos) << e.what();
  }
  GpioDigitalInputConfig key;
  key.line.offset = 3;  // an offset without a chip
  EXPECT_THROW(GpioDigitalInput k(key), std::runtime_error);
  GpioEstopInputConfig estop;
  estop.line.name = "weedspray-no-such-estop";
  try {
    GpioEstopInput e(estop);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("weedspray-no-such-estop"), std::string::npos) << e.what();
  }
  GpioOutputBankConfig empty;
  EXPECT_THROW(GpioOutputBank b(empty), std::runtime_error);
}

TEST(V4l2Camera, MissingDeviceIsAnErrorNotAThrow) {
  MonotonicClock clock;
  V4l2CameraConfig config;
  config.device = "/dev/video-weedspray-none";
  V4l2Camera camera(config, clock);
  EXPECT_FALSE(camera.start());
  EXPECT_NE(camera.last_error().find("/dev/video-weedspray-none"), std::string::npos)
      << camera.last_error();
  Frame frame;
  EXPECT_EQ(camera.next_frame(frame, 10ms), FrameStatus::kError);
  // A regular file is not a V4L2 device.
  config.device = "/proc/self/status";
  V4l2Camera not_a_camera(config, clock);
  EXPECT_FALSE(not_a_camera.start());
  EXPECT_FALSE(not_a_camera.last_error().empty());
}

TEST(V4l2Camera, PixelFormatNames) {
  EXPECT_EQ(parse_camera_pixel_format("YUYV"), CameraPixelFormat::kYuyv);
  EXPECT_EQ(parse_camera_pixel_format("mjpeg"), CameraPixelFormat::kMjpeg);
  EXPECT_EQ(parse_camera_pixel_format("grey"), CameraPixelFormat::kGrey);
  EXPECT_EQ(parse_camera_pixel_format("rgb24"), CameraPixelFormat::kRgb24);
  EXPECT_THROW(parse_camera_pixel_format("h264"), std::invalid_argument);
}

TEST(MonotonicClock, SleepsToAbsoluteDeadlines) {
  MonotonicClock clock;
  const auto t0 = clock.now();
  clock.sleep_until(t0 + 2ms);
  EXPECT_GE(clock.now(), t0 + 2ms);
  clock.sleep_until(t0);  // in the past: returns at once
}

}  // namespace
}  // namespace weedspray::io::hw
