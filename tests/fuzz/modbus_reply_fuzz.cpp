// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: arbitrary bytes as the reply on the serial line to the daemon's Modbus
// readers (the tank level sensor and the analog converter module), through a pty and
// libmodbus exactly as on an RS-485 adapter. A reply must never crash a reader, hang it past
// its timeouts, or come out as an accepted value outside its range; after any garbage the next
// well-formed reply must be read.
#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "io/linux/modbus_analog.hpp"
#include "io/linux/modbus_tank_level.hpp"
#include "io/linux/monotonic_clock.hpp"

namespace {

using namespace std::chrono_literals;

struct Line {
  int master = -1;  // the fuzzer's end: it writes replies and drains requests
  std::string device;
  weedspray::io::hw::MonotonicClock clock;
  std::unique_ptr<weedspray::io::hw::ModbusTankLevel> tank;
  std::unique_ptr<weedspray::io::hw::ModbusAnalogInput> adc;

  Line() {
    master = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (master < 0 || ::grantpt(master) != 0 || ::unlockpt(master) != 0) std::abort();
    device = ::ptsname(master);
    weedspray::io::hw::ModbusTankLevelConfig t;
    t.device = device;
    t.response_timeout = 5ms;  // short: every exec waits at most a few ms for a cut reply
    t.byte_timeout = 2ms;
    tank = std::make_unique<weedspray::io::hw::ModbusTankLevel>(t, clock);
    weedspray::io::hw::ModbusAnalogInputConfig a;
    a.port.device = device;
    a.port.response_timeout = 5ms;
    a.port.byte_timeout = 2ms;
    adc = std::make_unique<weedspray::io::hw::ModbusAnalogInput>(a, clock);
  }
  void drain() const {
    char buffer[512];
    while (::read(master, buffer, sizeof buffer) > 0) {
    }
  }
  void send(const std::uint8_t* data, std::size_t size) const {
    while (size > 0) {
      const ssize_t n = ::write(master, data, size);
      if (n <= 0) return;  // pty buffer full: the rest is lost, as on a line
      data += n;
      size -= static_cast<std::size_t>(n);
    }
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Line line;
  if (size == 0) return 0;
  line.drain();
  line.send(data + 1, size - 1);
  if (data[0] & 1) {
    const weedspray::io::TankLevelSample s = line.tank->read();
    if (s.ok && !(s.level_pct >= 0.0 && s.level_pct <= 100.0)) __builtin_trap();
  } else {
    const weedspray::io::AnalogSample s = line.adc->read();
    if (s.ok && !(std::isfinite(s.volts) && s.volts >= 0.0 && s.volts <= 65.535 + 1e-9))
      __builtin_trap();
  }
  line.drain();
  return 0;
}
