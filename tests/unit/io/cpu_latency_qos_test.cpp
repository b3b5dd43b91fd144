// SPDX-License-Identifier: Apache-2.0
// The PM QoS request: what it writes, that it holds the file open, and a clear error when it
// cannot (a stand-in file replaces /dev/cpu_dma_latency, which needs root).
#include "io/linux/cpu_latency_qos.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>

namespace weedspray::io::hw {
namespace {

std::filesystem::path temp_file(const char* name) {
  const auto path = std::filesystem::temp_directory_path() / name;
  std::ofstream(path).flush();
  return path;
}

TEST(CpuLatencyRequest, WritesTheLatencyAsABinaryS32AndHoldsTheFile) {
  const auto path = temp_file("weedspray_cpu_dma_latency_test");
  {
    CpuLatencyRequest request(25, path.string());
    EXPECT_TRUE(request.active()) << request.error();
    CpuLatencyRequest moved = std::move(request);
    EXPECT_TRUE(moved.active());
    EXPECT_FALSE(request.active());  // NOLINT(bugprone-use-after-move): the moved-from state
    std::ifstream in(path, std::ios::binary);
    std::int32_t value = -1;
    in.read(reinterpret_cast<char*>(&value), sizeof value);
    EXPECT_EQ(value, 25);
  }
  std::filesystem::remove(path);
}

TEST(CpuLatencyRequest, AMissingFileIsAnInactiveRequestNamingThePath) {
  CpuLatencyRequest request(0, "/nonexistent/cpu_dma_latency");
  EXPECT_FALSE(request.active());
  EXPECT_NE(request.error().find("/nonexistent/cpu_dma_latency"), std::string::npos)
      << request.error();
}

}  // namespace
}  // namespace weedspray::io::hw
