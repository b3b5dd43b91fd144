// SPDX-License-Identifier: Apache-2.0
#include "tests/integration/io/modbus_peer.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <thread>

extern char** environ;

namespace weedspray::test {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {
constexpr const char* kPython = "/usr/bin/python3";
const std::string kSlaveScript = std::string(WEEDSPRAY_IO_TEST_DIR) + "/modbus_slave.py";
}  // namespace

Child::Child(const std::vector<std::string>& argv, const fs::path& stdout_file,
             bool own_process_group)
    : group_(own_process_group) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, stdout_file.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  if (group_) {
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attr, 0);
  }
  const int rc = posix_spawn(&pid_, args[0], &actions, &attr, args.data(), environ);
  posix_spawnattr_destroy(&attr);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) pid_ = -1;
}

void Child::stop() {
  if (pid_ <= 0) return;
  const pid_t target = group_ ? -pid_ : pid_;
  kill(target, SIGTERM);
  bool exited = false;
  for (int i = 0; i < 50 && !exited; ++i) {
    exited = waitpid(pid_, nullptr, WNOHANG) == pid_;
    if (!exited) std::this_thread::sleep_for(20ms);
  }
  if (group_) {
    kill(target, SIGKILL);  // whatever of the group is left (gpsfake's gpsd)
  } else if (!exited) {
    kill(pid_, SIGKILL);
  }
  if (!exited) waitpid(pid_, nullptr, 0);
  pid_ = -1;
}

bool Child::running() const {
  return pid_ > 0 && waitpid(pid_, nullptr, WNOHANG) == 0;
}

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

void ModbusPeerTest::SetUp() {
  ASSERT_TRUE(fs::exists("/usr/bin/socat"))
      << "socat is required for the Modbus integration test (apt-get install socat; "
         "./dev deps installs it)";
  ASSERT_TRUE(fs::exists(kPython)) << kPython << " is required";
  ASSERT_EQ(std::system(
                (std::string(kPython) + " -c 'import pymodbus, serial, serial_asyncio' 2>/dev/null")
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

void ModbusPeerTest::TearDown() {
  slave_process_.reset();
  socat_.reset();
  std::error_code ec;
  if (!dir_.empty()) fs::remove_all(dir_, ec);
}

void ModbusPeerTest::start_slave(const std::vector<std::string>& args) {
  std::vector<std::string> argv{kPython, kSlaveScript, slave_.string()};
  argv.insert(argv.end(), args.begin(), args.end());
  slave_process_ = std::make_unique<Child>(argv, dir_ / "slave.log");
  ASSERT_TRUE(slave_process_->started());
  ASSERT_TRUE(wait_for(
      [&] { return read_file(dir_ / "slave.log").find("ready") != std::string::npos; }, 10s))
      << "the Modbus peer did not start: " << read_file(dir_ / "slave.log");
}

std::string ModbusPeerTest::slave_log() const {
  return read_file(dir_ / "slave.log");
}

}  // namespace weedspray::test
