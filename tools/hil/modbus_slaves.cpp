// SPDX-License-Identifier: Apache-2.0
#include "tools/hil/modbus_slaves.hpp"

#include <fcntl.h>
#include <grp.h>
#include <modbus/modbus.h>
#include <pthread.h>
#include <pty.h>
#include <sched.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace weedspray::hil {
namespace {

constexpr int kRegisters = 16;

struct Pty {
  int master = -1;
  int slave = -1;  // kept open: the master reads EIO while no one holds the slave side
};

// A raw pty pair, its slave side reachable as `link`, readable and writable by group dialout
// (the unit's serial-port group).
Pty open_pty(const std::string& link) {
  Pty pty;
  struct termios raw {};
  cfmakeraw(&raw);
  if (openpty(&pty.master, &pty.slave, nullptr, &raw, nullptr) != 0)
    throw std::runtime_error(std::string("openpty: ") + std::strerror(errno));
  const char* name = ttyname(pty.slave);
  if (name == nullptr) throw std::runtime_error("ttyname of the pty failed");
  if (const struct group* dialout = getgrnam("dialout"))
    if (fchown(pty.slave, static_cast<uid_t>(-1), dialout->gr_gid) != 0)
      throw std::runtime_error(std::string("fchown pty: ") + std::strerror(errno));
  if (fchmod(pty.slave, 0660) != 0)
    throw std::runtime_error(std::string("fchmod pty: ") + std::strerror(errno));
  ::unlink(link.c_str());
  if (::symlink(name, link.c_str()) != 0)
    throw std::runtime_error("symlink " + link + ": " + std::strerror(errno));
  return pty;
}

modbus_t* slave_context(const Pty& pty, int slave_id) {
  // The device name is never opened: the context talks on the pty master (modbus_set_socket).
  modbus_t* ctx = modbus_new_rtu("/dev/null", 115200, 'N', 8, 1);
  if (ctx == nullptr) throw std::runtime_error("modbus_new_rtu failed");
  modbus_set_slave(ctx, slave_id);
  modbus_set_socket(ctx, pty.master);
  return ctx;
}

void raise_priority() {
  // Answers inside the daemon's response timeout while the emulated CPUs are busy; ignored
  // where not permitted.
  struct sched_param param {};
  param.sched_priority = 60;
  pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
}

void serve_tank(Pty pty, ModbusBusConfig config, ModbusBoard& board) {
  raise_priority();
  modbus_t* ctx = slave_context(pty, config.tank_id);
  modbus_mapping_t* mapping = modbus_mapping_new(0, 0, kRegisters, 0);
  std::array<std::uint8_t, MODBUS_RTU_MAX_ADU_LENGTH> query{};
  for (;;) {
    const int length = modbus_receive(ctx, query.data());
    if (length <= 0) {
      if (length < 0) ::usleep(1000);  // the daemon has the port closed
      continue;
    }
    {
      std::lock_guard lock(board.mutex);
      ++board.tank_requests;
      mapping->tab_registers[config.register_address] = board.tank_counts;
    }
    modbus_reply(ctx, query.data(), length, mapping);
  }
}

}  // namespace

void start_tank_bus(const ModbusBusConfig& config, ModbusBoard& board) {
  std::thread(serve_tank, open_pty(config.link), config, std::ref(board)).detach();
}

}  // namespace weedspray::hil
