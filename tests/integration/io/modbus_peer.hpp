// SPDX-License-Identifier: Apache-2.0
// The Modbus peer fixture of the integration tests: a socat pty pair and, on its far end,
// tests/integration/io/modbus_slave.py (Debian's pymodbus RTU server, or a slave that is silent,
// sends bad CRCs or junk). socat and pymodbus are REQUIRED: SetUp fails (never skips) when they
// are missing; `./dev deps` installs them.
#pragma once

#include <gtest/gtest.h>
#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace weedspray::test {

// A child process, killed (by its pid) when the object goes away or stop() is called. With
// own_process_group it leads a process group of its own and the whole group is killed (a
// child that starts helpers of its own, as gpsfake starts gpsd).
class Child {
 public:
  Child(const std::vector<std::string>& argv, const std::filesystem::path& stdout_file,
        bool own_process_group = false);
  ~Child() { stop(); }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  bool started() const { return pid_ > 0; }
  bool running() const;
  void stop();  // SIGTERM, then SIGKILL after 1 s

 private:
  pid_t pid_ = -1;
  bool group_ = false;
};

std::string read_file(const std::filesystem::path& p);
bool wait_for(const std::function<bool()>& condition, std::chrono::milliseconds limit);

// master_ is the pty the code under test opens; the peer sits on slave_.
class ModbusPeerTest : public ::testing::Test {
 protected:
  void SetUp() override;
  void TearDown() override;
  // modbus_slave.py's arguments after the port, e.g. {"normal", "7", "0=523"}.
  void start_slave(const std::vector<std::string>& args);
  std::string slave_log() const;

  std::filesystem::path dir_, master_, slave_;
  std::unique_ptr<Child> socat_;
  std::unique_ptr<Child> slave_process_;
};

}  // namespace weedspray::test
