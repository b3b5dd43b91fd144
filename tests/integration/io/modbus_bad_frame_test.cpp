// SPDX-License-Identifier: Apache-2.0
// A bad frame on the pressure converters' Modbus line: the analog input flushes and is ready at
// once (the sample goes stale after three 10 ms loop periods, so it cannot sleep a 300 ms
// response timeout the way libmodbus's protocol recovery does), and the next read succeeds.
// The slave is this test, on the master side of a pty: it answers the first request with a
// corrupt frame and the second with a correct one.
#include <fcntl.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

#include "io/linux/modbus_analog.hpp"
#include "io/linux/monotonic_clock.hpp"

namespace weedspray::io::hw {
namespace {

using namespace std::chrono_literals;

std::uint16_t crc16(const std::vector<std::uint8_t>& bytes) {
  std::uint16_t crc = 0xFFFF;
  for (std::uint8_t b : bytes) {
    crc ^= b;
    for (int i = 0; i < 8; ++i) crc = (crc & 1) ? (crc >> 1) ^ 0xA001 : crc >> 1;
  }
  return crc;
}

// Reads one 8-byte RTU request (slave, function, address, count, CRC) from the pty master.
bool read_request(int fd) {
  std::array<std::uint8_t, 8> request{};
  std::size_t got = 0;
  const auto deadline = std::chrono::steady_clock::now() + 2s;
  while (got < request.size() && std::chrono::steady_clock::now() < deadline) {
    const ssize_t n = ::read(fd, request.data() + got, request.size() - got);
    if (n > 0)
      got += static_cast<std::size_t>(n);
    else
      std::this_thread::sleep_for(1ms);
  }
  return got == request.size();
}

TEST(ModbusAnalogInput, ABadFrameIsFlushedAtOnceAndTheNextReadSucceeds) {
  int master = -1, slave = -1;
  char name[64] = {};
  ASSERT_EQ(::openpty(&master, &slave, name, nullptr, nullptr), 0);
  termios raw{};
  ::tcgetattr(master, &raw);
  ::cfmakeraw(&raw);
  ::tcsetattr(master, TCSANOW, &raw);
  ::fcntl(master, F_SETFL, O_NONBLOCK);

  std::thread peer([master] {
    // First answer: a well-formed frame of another function (03 to an 04 request): libmodbus's
    // protocol recovery would sleep a response timeout on it.
    if (!read_request(master)) return;
    std::vector<std::uint8_t> wrong{1, 3, 2, 0x04, 0xD2};
    const std::uint16_t wrong_crc = crc16(wrong);
    wrong.push_back(wrong_crc & 0xFF);
    wrong.push_back(wrong_crc >> 8);
    (void)!::write(master, wrong.data(), wrong.size());
    // Second: 1234 counts, correct.
    if (!read_request(master)) return;
    std::vector<std::uint8_t> good{1, 4, 2, 0x04, 0xD2};
    const std::uint16_t crc = crc16(good);
    good.push_back(crc & 0xFF);
    good.push_back(crc >> 8);
    (void)!::write(master, good.data(), good.size());
  });

  MonotonicClock clock;
  ModbusAnalogInputConfig config;
  config.port.device = name;
  config.port.baud = 115200;
  config.port.response_timeout = 300ms;
  config.volts_per_count = 0.001;
  ModbusAnalogInput adc(config, clock);

  const auto t0 = std::chrono::steady_clock::now();
  const AnalogSample bad = adc.read();
  const auto bad_took = std::chrono::steady_clock::now() - t0;
  EXPECT_FALSE(bad.ok);
  EXPECT_FALSE(adc.last_error().empty());
  EXPECT_LT(bad_took, 100ms) << "a bad frame must not cost a response timeout (300 ms)";

  const AnalogSample good = adc.read();
  EXPECT_TRUE(good.ok) << adc.last_error();
  EXPECT_NEAR(good.volts, 1.234, 1e-9);
  peer.join();
  ::close(slave);
  ::close(master);
}

}  // namespace
}  // namespace weedspray::io::hw
