// The Modbus tank level reader against independent peers: Debian's pymodbus RTU server and
// misbehaving slaves, over a socat pty pair. socat and pymodbus are REQUIRED: the test fails
// (never skips) when they are missing; `./dev deps` installs them.
#include "io/linux/modbus_tank_level.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "io/linux/modbus_analog.hpp"
#include "io/linux/monotonic_clock.hpp"

extern char** environ;

namespace weedspray::io::hw {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

constexpr const char* kPython = "/usr/bin/python3";
const std::string kSlaveScript = std::string(WEEDSPRAY_IO_TEST_DIR) + "/modbus_slave.py";

// A child process, killed (by its pid) when the object goes away.
class Child {
 public:
  Child(const std::vector<std::string>& argv, const fs::path& stdout_file) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, stdout_file.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    const int rc = posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) pid_ = -1;
  }
  ~Child() {
    if (pid_ <= 0) return;
    kill(pid_, SIGTERM);
    for (int i = 0; i < 50; ++i) {
      if (waitpid(pid_, nullptr, WNOHANG) == pid_) return;
      std::this_thread::sleep_for(20ms);
    }
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  bool started() const { return pid_ > 0; }
  bool running() const { return pid_ > 0 && waitpid(pid_, nullptr, WNOHANG) == 0; }

 private:
  pid_t pid_ = -1;
};

std::string read_file(const fs::path& p) {
  std::FILE* f = std::fopen(p.c_str(), "r");
  if (!f) return {};
  std::string out;
  char buf[512];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) out.append(buf, n);
  std::fclose(f);
  return out;
}

bool wait_for(const std::function<bool()>& condition, std::chrono::milliseconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (condition()) return true;
    std::this_thread::sleep_for(20ms);
  }
  return condition();
}

class ModbusPeer : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists("/usr/bin/socat"))
        << "socat is required for the Modbus integration test (apt-get install socat; "
           "./dev deps installs it)";
    ASSERT_TRUE(fs::exists(kPython)) << kPython << " is required";
    ASSERT_EQ(std::system((std::string(kPython) +
                           " -c 'import pymodbus, serial, serial_asyncio' 2>/dev/null")
                              .c_str()),
              0)
        << "Debian's python3-pymodbus, python3-serial and python3-serial-asyncio are required "
           "for the Modbus integration test (./dev deps installs them)";
    char tmpl[] = "/tmp/weedspray-modbus-XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    master_ = dir_ / "master";
    slave_ = dir_ / "slave";
    socat_ =
        std::make_unique<Child>(std::vector<std::string>{"/usr/bin/socat", "-d", "-d",
                                                         "pty,raw,echo=0,link=" + master_.string(),
                                                         "pty,raw,echo=0,link=" + slave_.string()},
                                dir_ / "socat.log");
    ASSERT_TRUE(socat_->started());
    ASSERT_TRUE(wait_for([&] { return fs::exists(master_) && fs::exists(slave_); }, 5s))
        << "socat did not create the pty pair: " << read_file(dir_ / "socat.log");
  }

  void TearDown() override {
    slave_process_.reset();
    socat_.reset();
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }

  void start_slave(const std::vector<std::string>& args) {
    std::vector<std::string> argv{kPython, kSlaveScript, slave_.string()};
    argv.insert(argv.end(), args.begin(), args.end());
    slave_process_ = std::make_unique<Child>(argv, dir_ / "slave.log");
    ASSERT_TRUE(slave_process_->started());
    ASSERT_TRUE(wait_for(
        [&] { return read_file(dir_ / "slave.log").find("ready") != std::string::npos; }, 10s))
        << "the Modbus peer did not start: " << read_file(dir_ / "slave.log");
  }

  ModbusTankLevelConfig config(int register_address = 0) const {
    ModbusTankLevelConfig c;
    c.device = master_.string();
    c.baud = 9600;
    c.slave_id = 7;
    c.register_address = register_address;
    c.percent_per_count = 0.1;
    c.response_timeout = 300ms;
    return c;
  }

  std::string slave_log() const { return read_file(dir_ / "slave.log"); }

  fs::path dir_, master_, slave_;
  std::unique_ptr<Child> socat_;
  std::unique_ptr<Child> slave_process_;
  MonotonicClock clock_;
};

// pymodbus needs a moment after "ready" before it serves: the first good read may take a few.
TankLevelSample first_ok(ModbusTankLevel& sensor, int attempts) {
  TankLevelSample s;
  for (int i = 0; i < attempts; ++i) {
    s = sensor.read();
    if (s.ok) break;
  }
  return s;
}

TEST_F(ModbusPeer, ReadsTheLevelFromAPymodbusSlave) {
  start_slave({"normal", "7", "0=523", "1=2000"});
  ModbusTankLevel sensor(config(0), clock_);
  const TankLevelSample s = first_ok(sensor, 20);
  ASSERT_TRUE(s.ok) << sensor.last_error() << "\nslave: " << slave_log();
  EXPECT_NEAR(s.level_pct, 52.3, 1e-9);
  EXPECT_GT(s.time.count(), 0);
  for (int i = 0; i < 5; ++i) {
    const TankLevelSample again = sensor.read();
    EXPECT_TRUE(again.ok) << sensor.last_error();
    EXPECT_NEAR(again.level_pct, 52.3, 1e-9);
  }
  // Input registers hold the same values in this peer.
  ModbusTankLevelConfig input = config(0);
  input.register_type = ModbusRegisterType::kInput;
  ModbusTankLevel input_sensor(input, clock_);
  const TankLevelSample in = first_ok(input_sensor, 5);
  ASSERT_TRUE(in.ok) << input_sensor.last_error();
  EXPECT_NEAR(in.level_pct, 52.3, 1e-9);
}

TEST_F(ModbusPeer, OutOfRangeLevelIsInvalidNotALevel) {
  start_slave({"normal", "7", "0=523", "1=2000"});
  ModbusTankLevel good(config(0), clock_);
  ASSERT_TRUE(first_ok(good, 20).ok) << good.last_error();
  ModbusTankLevel sensor(config(1), clock_);  // 2000 * 0.1 = 200 % > 100 %
  const TankLevelSample s = sensor.read();
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.invalid_responses, 1U);
  EXPECT_NE(sensor.last_error().find("out of range"), std::string::npos) << sensor.last_error();
}

TEST_F(ModbusPeer, WrongSlaveIdTimesOut) {
  start_slave({"normal", "7", "0=523"});
  ModbusTankLevelConfig c = config(0);
  c.slave_id = 9;  // nobody answers for 9
  ModbusTankLevel sensor(c, clock_);
  const TankLevelSample s = sensor.read();
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.timeouts, 1U) << sensor.last_error();
}

TEST_F(ModbusPeer, SilentSlaveCountsTimeoutsWithoutHanging) {
  start_slave({"silent"});
  ModbusTankLevel sensor(config(0), clock_);
  const auto t0 = std::chrono::steady_clock::now();
  TankLevelSample s;
  for (int i = 0; i < 3; ++i) s = sensor.read();
  const auto elapsed = std::chrono::steady_clock::now() - t0;
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.reads, 3U);
  EXPECT_EQ(s.timeouts, 3U) << sensor.last_error();
  EXPECT_NE(sensor.last_error().find("timed out"), std::string::npos) << sensor.last_error();
  // Each read is bounded by the 300 ms response timeout (plus libmodbus's recovery wait).
  EXPECT_LT(elapsed, 3s);
}

TEST_F(ModbusPeer, BadCrcAnswersAreCountedAsCrcErrors) {
  start_slave({"badcrc", "7"});
  ModbusTankLevel sensor(config(0), clock_);
  TankLevelSample s;
  for (int i = 0; i < 3; ++i) s = sensor.read();
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.crc_errors, 3U) << sensor.last_error() << " timeouts " << s.timeouts << " invalid "
                              << s.invalid_responses;
}

TEST_F(ModbusPeer, JunkAnswersAreErrorsNeverALevel) {
  start_slave({"junk"});
  ModbusTankLevel sensor(config(0), clock_);
  const auto t0 = std::chrono::steady_clock::now();
  TankLevelSample s;
  for (int i = 0; i < 10; ++i) {
    s = sensor.read();
    EXPECT_FALSE(s.ok) << "junk decoded as level " << s.level_pct;
  }
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 15s);
  EXPECT_EQ(s.reads, 10U);
  EXPECT_EQ(s.timeouts + s.crc_errors + s.invalid_responses + s.other_errors, 10U);
  EXPECT_FALSE(sensor.last_error().empty());
}

TEST_F(ModbusPeer, RecoversWhenTheSlaveComesBack) {
  ModbusTankLevel sensor(config(0), clock_);
  EXPECT_FALSE(sensor.read().ok) << "no slave yet";
  start_slave({"normal", "7", "0=640"});
  const TankLevelSample s = first_ok(sensor, 20);
  ASSERT_TRUE(s.ok) << sensor.last_error();
  EXPECT_NEAR(s.level_pct, 64.0, 1e-9);
  EXPECT_GE(s.timeouts, 1U);
}

TEST_F(ModbusPeer, AnalogModuleInputAndOutputRoundTrip) {
  start_slave({"normal", "7", "0=523", "2=1234"});
  ModbusTankLevel probe(config(0), clock_);  // waits until the peer serves
  ASSERT_TRUE(first_ok(probe, 20).ok) << probe.last_error();

  const ModbusRtuSettings port{master_.string(), 9600, 'N', 8, 1, 7, 300ms};
  ModbusAnalogInput adc({port, 2, true, 0.001}, clock_);
  const AnalogSample in = adc.read();
  ASSERT_TRUE(in.ok) << adc.last_error();
  EXPECT_NEAR(in.volts, 1.234, 1e-9);

  {
    ModbusAnalogOutput dac({port, 5, 0.001, 10.0, 0.5});  // writes the safe 0.5 V at start
    ModbusAnalogInput readback({port, 5, false, 0.001}, clock_);
    EXPECT_NEAR(readback.read().volts, 0.5, 1e-9);
    EXPECT_EQ(dac.write(2.5), 0);
    EXPECT_NEAR(readback.read().volts, 2.5, 1e-9);
    EXPECT_EQ(dac.write(99.0), 0);
    EXPECT_NEAR(readback.read().volts, 10.0, 1e-9) << "clamped to full scale";
  }
  ModbusAnalogInput readback({port, 5, false, 0.001}, clock_);
  EXPECT_NEAR(readback.read().volts, 0.5, 1e-9) << "destructor forces safe";
}

TEST_F(ModbusPeer, AnalogInputCountsErrorsOnASilentModule) {
  start_slave({"silent"});
  ModbusAnalogInput adc({{master_.string(), 9600, 'N', 8, 1, 7, 200ms}, 0, true, 0.001}, clock_);
  AnalogSample s = adc.read();
  s = adc.read();
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.error_count, 2U);
}

TEST(ModbusTankLevelConfig, ClearErrorsForBadDeviceAndSettings) {
  MonotonicClock clock;
  ModbusTankLevelConfig c;
  c.device = "/dev/ttyNOPE-weedspray";
  try {
    ModbusTankLevel sensor(c, clock);
    FAIL() << "expected an error for a missing serial port";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/ttyNOPE-weedspray"), std::string::npos) << e.what();
  }
  c.parity = 'X';
  try {
    ModbusTankLevel sensor(c, clock);
    FAIL() << "expected an error for parity X";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("parity"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace weedspray::io::hw
