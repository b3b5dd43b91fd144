// SPDX-License-Identifier: Apache-2.0
// The records_disk_full condition and the free-space reading behind it.
#include "daemon/records/records_space.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <filesystem>

namespace weedspray::daemon {
namespace {

namespace fs = std::filesystem;

TEST(RecordsSpace, AtRiskWhileWritesFailLinesWaitOrSpaceIsUnderTheFloor) {
  const std::uint64_t floor = 64'000'000;
  EXPECT_FALSE(records_at_risk({}, floor + 1, floor));
  EXPECT_TRUE(records_at_risk({}, floor - 1, floor));
  EXPECT_FALSE(records_at_risk({}, std::nullopt, floor)) << "unknown space alone is no alarm";
  EXPECT_TRUE(records_at_risk({.error = ENOSPC}, floor + 1, floor));
  EXPECT_TRUE(records_at_risk({.held_lines = 1}, floor + 1, floor));
  EXPECT_FALSE(records_at_risk({.dropped_lines = 3}, floor + 1, floor))
      << "lines dropped earlier do not hold the alarm once writing works";
  const std::optional<std::uint64_t> free_here = available_bytes(fs::temp_directory_path());
  ASSERT_TRUE(free_here.has_value());
  EXPECT_GT(*free_here, 0U);
  EXPECT_FALSE(available_bytes("/nonexistent/weedspray").has_value());
}

}  // namespace
}  // namespace weedspray::daemon
