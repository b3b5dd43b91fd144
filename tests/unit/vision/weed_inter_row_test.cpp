// SPDX-License-Identifier: Apache-2.0
// The inter-row rule on synthetic crop rows: peaks, bands, tracking a drifting row, frames
// where the rows are missing, and re-acquisition.
#include "vision/weed_inter_row.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "allocation_counter.hpp"
#include "test_images.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::vision {
namespace {

using test::BgrFrame;

constexpr int kWidth = 200;
constexpr int kHeight = 100;

void fill_rect(BgrFrame& frame, int x0, int y0, int x1, int y1, test::Bgr colour) {
  for (int y = std::max(0, y0); y < std::min(frame.height, y1); ++y) {
    for (int x = std::max(0, x0); x < std::min(frame.width, x1); ++x) frame.set(x, y, colour);
  }
}

// Soil with 16-px-wide crop rows centred on `rows` (columns) and 5x5 weeds at `weeds`.
BgrFrame field(const std::vector<int>& rows, const std::vector<int>& weeds) {
  BgrFrame frame(kWidth, kHeight, test::kSoil);
  for (int centre : rows) fill_rect(frame, centre - 8, 0, centre + 8, kHeight, test::kPlant);
  for (int x : weeds) fill_rect(frame, x - 2, 40, x + 3, 45, test::kPlant);
  return frame;
}

// Columns of the confirmed crop rows' centres.
std::vector<double> confirmed_rows(const Pipeline& pipeline) {
  std::vector<double> centres;
  for (const CropRow& row : pipeline.crop_rows()) {
    if (row.confirmed) centres.push_back(row.position * kWidth);
  }
  return centres;
}

PipelineConfig inter_row_config() {
  PipelineConfig config = default_pipeline_config();
  config.weed_source = WeedSource::kInterRow;
  config.rows = 1;
  config.cols = 4;
  config.inter_row_rule.row_band_fraction = 0.16;  // 32 px of 200
  return config;
}

TEST(RowPeaks, TallColumnsArePeaksAndSmallBumpsAreNot) {
  std::vector<std::uint32_t> counts(100, 0);
  for (int x = 18; x < 23; ++x) counts[x] = 90;  // row at 20
  for (int x = 68; x < 73; ++x) counts[x] = 80;  // row at 70
  counts[45] = 10;                               // a weed: below a third of the tallest
  InterRowRule rule;
  rule.row_band_fraction = 0.1;
  std::vector<double> scratch;
  std::array<double, kMaxCropRows> peaks{};
  ASSERT_EQ(find_row_peaks(counts, rule, scratch, peaks), 2u);
  EXPECT_NEAR(peaks[0], 0.205, 0.011);
  EXPECT_NEAR(peaks[1], 0.705, 0.011);

  // Two peaks closer than min_row_spacing are one row: the taller one.
  rule.min_row_spacing = 0.6;
  ASSERT_EQ(find_row_peaks(counts, rule, scratch, peaks), 1u);
  EXPECT_NEAR(peaks[0], 0.205, 0.011);

  std::vector<std::uint32_t> empty(100, 0);
  EXPECT_EQ(find_row_peaks(empty, rule, scratch, peaks), 0u);
}

TEST(InterRowRule, VegetationInRowBandsIsCropAndBetweenRowsIsWeed) {
  Pipeline pipeline(inter_row_config());
  const BgrFrame frame = field({40, 140}, {90, 185});
  const FrameResult& result = pipeline.process(frame.view());
  ASSERT_TRUE(pipeline.last_frame_ok()) << pipeline.last_error();
  // Zones are 50 px wide: rows in zones 0 and 2, weeds in zones 1 and 3.
  const double zone_pixels = 50.0 * kHeight;
  EXPECT_DOUBLE_EQ(result.crop_density[0], 16 * kHeight / zone_pixels);
  EXPECT_DOUBLE_EQ(result.zone_density[0], 0.0);
  EXPECT_DOUBLE_EQ(result.zone_density[1], 25 / zone_pixels);
  EXPECT_DOUBLE_EQ(result.crop_density[1], 0.0);
  EXPECT_DOUBLE_EQ(result.crop_density[2], 16 * kHeight / zone_pixels);
  EXPECT_DOUBLE_EQ(result.zone_density[2], 0.0);
  EXPECT_DOUBLE_EQ(result.zone_density[3], 25 / zone_pixels);

  // The class map says the same pixel by pixel.
  const ImageView classes = pipeline.class_map();
  ASSERT_EQ(classes.width, kWidth);
  EXPECT_EQ(classes.data[50 * classes.stride + 40], kClassCrop);
  EXPECT_EQ(classes.data[42 * classes.stride + 90], kClassWeed);
  EXPECT_EQ(classes.data[10 * classes.stride + 90], kClassSoil);

  // The vegetation source calls all of it weed.
  PipelineConfig vegetation = inter_row_config();
  vegetation.weed_source = WeedSource::kVegetation;
  Pipeline green(vegetation);
  EXPECT_DOUBLE_EQ(green.process(frame.view()).zone_density[0], 16 * kHeight / zone_pixels);
}

TEST(InterRowRule, WeedsInsideTheBandAreCountedAsCrop) {
  // A weed 12 px from a row's centre lies inside a 32 px band: the rule cannot tell it.
  Pipeline pipeline(inter_row_config());
  const FrameResult& result = pipeline.process(field({40, 140}, {52}).view());
  EXPECT_DOUBLE_EQ(result.zone_density[1], 0.0);
  EXPECT_GT(result.crop_density[1], 0.0);
}

TEST(InterRowRule, TracksADriftingRow) {
  Pipeline pipeline(inter_row_config());
  // The left row drifts right by 2 px a frame (the camera yaws); a weed stays at x = 100.
  for (int frame_index = 0; frame_index < 20; ++frame_index) {
    const int left_row = 40 + 2 * frame_index;
    const FrameResult& result = pipeline.process(field({left_row, 160}, {105}).view());
    ASSERT_TRUE(pipeline.last_frame_ok());
    // The weed is always weed, the rows always crop (smoothing lags a couple of pixels).
    EXPECT_DOUBLE_EQ(result.zone_density[2], 25 / (50.0 * kHeight)) << "frame " << frame_index;
    ASSERT_EQ(pipeline.crop_rows().size(), 2u) << "frame " << frame_index;
    EXPECT_NEAR(pipeline.crop_rows()[0].position * kWidth, left_row, 4.0)
        << "frame " << frame_index;
  }
}

TEST(InterRowRule, RowsMissingFromAFrameAreKeptAndAPatchBetweenThemStaysWeed) {
  Pipeline pipeline(inter_row_config());
  for (int i = 0; i < 3; ++i) pipeline.process(field({40, 140}, {}).view());
  // A gap in both rows: only a weed patch between them is green. Found afresh, the patch
  // would be the tallest column and called a crop row.
  BgrFrame gap(kWidth, kHeight, test::kSoil);
  fill_rect(gap, 84, 20, 96, 80, test::kPlant);
  const FrameResult& result = pipeline.process(gap.view());
  ASSERT_TRUE(pipeline.last_frame_ok());
  EXPECT_DOUBLE_EQ(result.zone_density[1], 12 * 60 / (50.0 * kHeight));
  EXPECT_DOUBLE_EQ(result.crop_density[1], 0.0);
  // The patch is at most a tentative row beside the tracked ones.
  const std::vector<double> rows = confirmed_rows(pipeline);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_NEAR(rows[0], 40, 1.0);
  EXPECT_NEAR(rows[1], 140, 1.0);

  // Without tracking (a fresh start) the same frame makes the patch a row.
  pipeline.reset_tracking();
  EXPECT_DOUBLE_EQ(pipeline.process(gap.view()).zone_density[1], 0.0);
}

TEST(InterRowRule, RowsLostForLongAreReacquiredWhereTheyNowAre) {
  PipelineConfig config = inter_row_config();
  config.inter_row_rule.lost_after_frames = 3;
  Pipeline pipeline(config);
  pipeline.process(field({40, 140}, {}).view());
  const BgrFrame bare(kWidth, kHeight, test::kSoil);
  for (int i = 0; i < 3; ++i) pipeline.process(bare.view());
  EXPECT_EQ(pipeline.crop_rows().size(), 0u);
  // New rows (the sprayer moved to another bed) count at once.
  const FrameResult& result = pipeline.process(field({90, 190}, {}).view());
  ASSERT_EQ(pipeline.crop_rows().size(), 2u);
  EXPECT_NEAR(pipeline.crop_rows()[0].position * kWidth, 90, 1.0);
  EXPECT_DOUBLE_EQ(result.zone_density[1], 0.0);
  EXPECT_GT(result.crop_density[1], 0.0);
}

TEST(InterRowRule, ANewRowBesideTrackedOnesCountsOnlyOnceConfirmed) {
  PipelineConfig config = inter_row_config();
  config.inter_row_rule.confirm_frames = 2;
  Pipeline pipeline(config);
  pipeline.process(field({40}, {}).view());
  // A second row enters: first sighting is weed, the second makes it a row.
  EXPECT_GT(pipeline.process(field({40, 140}, {}).view()).zone_density[2], 0.0);
  EXPECT_DOUBLE_EQ(pipeline.process(field({40, 140}, {}).view()).zone_density[2], 0.0);
}

TEST(InterRowRule, NoAllocationOnceWarmedUp) {
  Pipeline pipeline(inter_row_config());
  const BgrFrame rows = field({40, 140}, {90});
  const BgrFrame gap = field({}, {90});
  pipeline.process(rows.view());  // warm-up: sizes the buffers
  const long before = weedspray::test::allocation_count();
  for (int i = 0; i < 5; ++i) pipeline.process((i % 2 ? gap : rows).view());
  EXPECT_EQ(weedspray::test::allocation_count(), before);
}

TEST(InterRowRule, BadRuleIsNamed) {
  PipelineConfig config = inter_row_config();
  config.inter_row_rule.row_band_fraction = 0.0;
  try {
    Pipeline pipeline(config);
    FAIL() << "accepted a zero band";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("row_band_fraction"), std::string::npos);
  }
}

}  // namespace
}  // namespace weedspray::vision
