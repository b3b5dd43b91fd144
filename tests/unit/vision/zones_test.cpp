// SPDX-License-Identifier: Apache-2.0
#include "vision/zones.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace weedspray::vision {
namespace {

TEST(DensityLevels, CutPointsAreUpperBoundsInclusive) {
  const DensityLevelCuts cuts;  // 0.005 0.02 0.05 0.10 0.20
  EXPECT_EQ(classify_density(0.0, cuts), DensityLevel::kNone);
  EXPECT_EQ(classify_density(0.005, cuts), DensityLevel::kNone);
  EXPECT_EQ(classify_density(0.0051, cuts), DensityLevel::kFew);
  EXPECT_EQ(classify_density(0.03, cuts), DensityLevel::kModerate);
  EXPECT_EQ(classify_density(0.07, cuts), DensityLevel::kMany);
  EXPECT_EQ(classify_density(0.15, cuts), DensityLevel::kSevere);
  EXPECT_EQ(classify_density(0.9, cuts), DensityLevel::kVerySevere);
  EXPECT_EQ(to_string(DensityLevel::kVerySevere), "very_severe");
}

TEST(DensityLevels, ConfigurableAndValidated) {
  DensityLevelCuts cuts;
  cuts.upper = {0.1, 0.2, 0.3, 0.4, 0.5};
  EXPECT_FALSE(validate_density_cuts(cuts).has_value());
  EXPECT_EQ(classify_density(0.25, cuts), DensityLevel::kModerate);
  cuts.upper = {0.1, 0.1, 0.3, 0.4, 0.5};
  EXPECT_TRUE(validate_density_cuts(cuts).has_value());
  cuts.upper = {0.1, 0.2, 0.3, 0.4, 1.5};
  EXPECT_TRUE(validate_density_cuts(cuts).has_value());
}

// Lateral histogram of two crop rows (peaks) with weeds between them (2018 paper, Eq. 8).
TEST(InterRow, IntervalsBelowAThirdOfTheMaxWithTheirShare) {
  //                                   crop      gap         crop    gap
  const std::vector<std::uint32_t> columns = {90, 60, 10, 20, 0, 30, 90, 45, 5, 5};
  InterRowMap map;
  find_inter_row_intervals(columns, 1000, 1.0 / 3.0, DensityLevelCuts{}, map);
  // max 90, limit 30: columns 2-5 (10 + 20 + 0 + 30 = 60) and 8-9 (10).
  ASSERT_EQ(map.count, 2u);
  EXPECT_EQ(map.intervals[0].first_column, 2);
  EXPECT_EQ(map.intervals[0].last_column, 5);
  EXPECT_DOUBLE_EQ(map.intervals[0].share, 0.060);
  EXPECT_EQ(map.intervals[0].level, DensityLevel::kMany);
  EXPECT_EQ(map.intervals[1].first_column, 8);
  EXPECT_EQ(map.intervals[1].last_column, 9);
  EXPECT_DOUBLE_EQ(map.intervals[1].share, 0.010);
  EXPECT_EQ(map.intervals[1].level, DensityLevel::kFew);
}

TEST(InterRow, EmptyMaskIsOneIntervalWithoutWeeds) {
  const std::vector<std::uint32_t> columns(50, 0);
  InterRowMap map;
  find_inter_row_intervals(columns, 500, 1.0 / 3.0, DensityLevelCuts{}, map);
  ASSERT_EQ(map.count, 1u);
  EXPECT_EQ(map.intervals[0].last_column, 49);
  EXPECT_EQ(map.intervals[0].share, 0.0);
  EXPECT_EQ(map.intervals[0].level, DensityLevel::kNone);
}

TEST(InterRow, IntervalsBeyondCapacityFoldIntoTheLast) {
  std::vector<std::uint32_t> columns;
  for (std::size_t i = 0; i < kMaxInterRowIntervals + 10; ++i) {
    columns.push_back(100);  // crop
    columns.push_back(1);    // gap with one weed pixel
  }
  InterRowMap map;
  find_inter_row_intervals(columns, 10000, 1.0 / 3.0, DensityLevelCuts{}, map);
  EXPECT_EQ(map.count, kMaxInterRowIntervals);
  double total = 0;
  for (const InterRowInterval& interval : map.view()) total += interval.share;
  EXPECT_DOUBLE_EQ(total, (kMaxInterRowIntervals + 10) / 10000.0);
  EXPECT_EQ(map.intervals[kMaxInterRowIntervals - 1].last_column,
            static_cast<int>(columns.size()) - 1);
}

}  // namespace
}  // namespace weedspray::vision
