// SPDX-License-Identifier: Apache-2.0
#include "vision/threshold.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

namespace weedspray::vision {
namespace {

ThresholdParams params_with_fixed(int level) {
  ThresholdParams params;
  params.fixed_threshold = level;
  return params;
}

// Two clean clusters: 2 px at 10, 1 px at 12, 3 px at 100.
Histogram two_clusters() {
  Histogram histogram{};
  histogram[10] = 2;
  histogram[12] = 1;
  histogram[100] = 3;
  return histogram;
}

// A Gaussian-shaped bump of `count` pixels around `mean`.
void add_bump(Histogram& histogram, double mean, double sigma, double count) {
  for (int level = 0; level < 256; ++level) {
    const double z = (level - mean) / sigma;
    histogram[level] += static_cast<std::uint32_t>(
        std::lround(count * std::exp(-0.5 * z * z) / (sigma * std::sqrt(2 * M_PI))));
  }
}

TEST(ThresholdNames, RoundTripAndRejectUnknown) {
  ASSERT_EQ(all_threshold_methods().size(), threshold_method_names().size());
  for (ThresholdMethod method : all_threshold_methods()) {
    EXPECT_EQ(parse_threshold_method(to_string(method)), method);
  }
  EXPECT_EQ(parse_threshold_method("fit"), ThresholdMethod::kFit);
  EXPECT_FALSE(parse_threshold_method("FIT").has_value());
}

TEST(BetweenClassVariance, HandComputed) {
  // Split at 12: w0 = w1 = 1/2, means 32/3 and 100: 1/4 * (89.333)^2 = 1995.11.
  EXPECT_NEAR(between_class_variance(two_clusters(), 12), 1995.111, 1e-3);
  // Split at 10: w0 = 1/3 (mean 10), w1 = 2/3 (mean 312/4 = 78): 2/9 * 68^2 = 1027.56.
  EXPECT_NEAR(between_class_variance(two_clusters(), 10), 1027.556, 1e-3);
  EXPECT_EQ(between_class_variance(two_clusters(), 200), 0.0);  // one class empty
}

TEST(Thresholds, TwoClustersHandComputed) {
  const Histogram histogram = two_clusters();
  const ThresholdParams params = params_with_fixed(50);
  // Otsu: the variance is flat for t in [12, 99]; the first maximum is 12.
  EXPECT_EQ(compute_threshold(histogram, ThresholdMethod::kOtsu, params).threshold, 12);
  // FIT: mean 332/6 = 55.33; means below/above 10.67 and 100 -> 55.33 again: converged, 55.
  EXPECT_EQ(compute_threshold(histogram, ThresholdMethod::kFit, params).threshold, 55);
  // K-means from centres 10 and 100: split 55, centres 10.67 and 100 -> 55.
  EXPECT_EQ(compute_threshold(histogram, ThresholdMethod::kKmeans, params).threshold, 55);
  EXPECT_EQ(compute_threshold(histogram, ThresholdMethod::kFixed, params).threshold, 50);
  for (ThresholdMethod method : all_threshold_methods()) {
    const ThresholdResult result = compute_threshold(histogram, method, params);
    EXPECT_TRUE(result.bimodal) << to_string(method);
    EXPECT_GE(result.threshold, 12) << to_string(method);
    EXPECT_LT(result.threshold, 100) << to_string(method);
  }
}

TEST(Thresholds, GaussianBimodalAgreesWithOtsu) {
  Histogram histogram{};
  add_bump(histogram, 80, 6, 60000);    // soil
  add_bump(histogram, 160, 10, 20000);  // plants
  const ThresholdParams params = params_with_fixed(120);
  const ThresholdResult otsu = compute_threshold(histogram, ThresholdMethod::kOtsu, params);
  ASSERT_TRUE(otsu.bimodal);
  EXPECT_GT(otsu.threshold, 100);
  EXPECT_LT(otsu.threshold, 140);
  // IPSO reaches Otsu's optimum fitness (the 2018 paper: 0.1 % error). The variance is nearly
  // flat across the empty gap between the modes, so the level itself may differ.
  const int ipso = compute_threshold(histogram, ThresholdMethod::kIpso, params).threshold;
  const double best = between_class_variance(histogram, otsu.threshold);
  EXPECT_GE(between_class_variance(histogram, ipso), best * 0.999);
  for (ThresholdMethod method : {ThresholdMethod::kFit, ThresholdMethod::kKmeans,
                                 ThresholdMethod::kHbt, ThresholdMethod::kPso}) {
    const ThresholdResult result = compute_threshold(histogram, method, params);
    EXPECT_TRUE(result.bimodal) << to_string(method);
    EXPECT_NEAR(result.threshold, otsu.threshold, 15) << to_string(method);
  }
  // HBT: the valley between the modes lies between them, nearer the narrow soil peak.
  const int hbt = compute_threshold(histogram, ThresholdMethod::kHbt, params).threshold;
  EXPECT_GT(hbt, 95);
  EXPECT_LT(hbt, 145);
}

TEST(Thresholds, PsoIsReproducibleForASeed) {
  Histogram histogram{};
  add_bump(histogram, 70, 12, 50000);
  add_bump(histogram, 150, 15, 30000);
  ThresholdParams params = params_with_fixed(120);
  for (ThresholdMethod method : {ThresholdMethod::kPso, ThresholdMethod::kIpso}) {
    const int first = compute_threshold(histogram, method, params).threshold;
    for (int repeat = 0; repeat < 5; ++repeat) {
      EXPECT_EQ(compute_threshold(histogram, method, params).threshold, first);
    }
  }
  // A 3-particle, 1-iteration swarm with another seed lands elsewhere: the seed matters.
  params.pso_particles = 3;
  params.pso_iterations = 1;
  std::set<int> results;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    params.seed = seed;
    results.insert(compute_threshold(histogram, ThresholdMethod::kPso, params).threshold);
  }
  EXPECT_GT(results.size(), 1u);
}

// Degenerate frames: never a split of one population, always the fixed level, not bimodal.
TEST(Thresholds, DegenerateHistogramsGiveTheFixedLevel) {
  Histogram empty{};
  Histogram uniform{};
  uniform[128] = 1000;  // black, white, grey card on the CIVE scale: one level
  Histogram black{};
  black[0] = 1000;
  Histogram saturated{};
  saturated[255] = 1000;
  Histogram two_levels{};  // quantisation noise of a flat surface
  two_levels[120] = 700;
  two_levels[121] = 300;
  const ThresholdParams params = params_with_fixed(131);
  for (const Histogram* histogram : {&empty, &uniform, &black, &saturated}) {
    for (ThresholdMethod method : all_threshold_methods()) {
      const ThresholdResult result = compute_threshold(*histogram, method, params);
      EXPECT_EQ(result.threshold, 131) << to_string(method);
      EXPECT_FALSE(result.bimodal) << to_string(method);
    }
  }
  for (ThresholdMethod method : all_threshold_methods()) {
    const ThresholdResult result = compute_threshold(two_levels, method, params);
    EXPECT_EQ(result.threshold, 131) << to_string(method);
  }
}

TEST(Thresholds, UnimodalBareSoilAndFullCanopyAreJudgedOnTheFixedScale) {
  Histogram bare_soil{};
  add_bump(bare_soil, 120, 3, 100000);
  Histogram full_canopy{};
  add_bump(full_canopy, 165, 8, 100000);
  const ThresholdParams params = params_with_fixed(131);
  for (ThresholdMethod method : all_threshold_methods()) {
    const ThresholdResult soil = compute_threshold(bare_soil, method, params);
    EXPECT_FALSE(soil.bimodal) << to_string(method);
    EXPECT_EQ(soil.threshold, 131) << to_string(method);  // no pixel above: no plants
    const ThresholdResult canopy = compute_threshold(full_canopy, method, params);
    EXPECT_FALSE(canopy.bimodal) << to_string(method);
    EXPECT_EQ(canopy.threshold, 131) << to_string(method);  // every pixel above: all plants
  }
  // The papers' behaviour on request: FIT then splits the soil near its mean.
  ThresholdParams keep = params;
  keep.unimodal = UnimodalPolicy::kKeepSplit;
  const ThresholdResult split = compute_threshold(bare_soil, ThresholdMethod::kFit, keep);
  EXPECT_FALSE(split.bimodal);
  EXPECT_NEAR(split.threshold, 120, 1);
}

TEST(LooksBimodal, SparsePlantsOnSoilAreBimodal) {
  Histogram histogram{};
  add_bump(histogram, 120, 3, 97000);
  add_bump(histogram, 160, 6, 3000);  // 3 % seedlings
  const ThresholdParams params = params_with_fixed(131);
  const ThresholdResult result = compute_threshold(histogram, ThresholdMethod::kOtsu, params);
  EXPECT_TRUE(result.bimodal);
  EXPECT_GT(result.threshold, 125);
  EXPECT_LT(result.threshold, 150);
}

// --- UnimodalPolicy::kClearOfPeak (CIVE's default) on histograms shaped like the field sets'
// CIVE histograms: soil a narrow peak (sigma about 1.5-2.5 levels) near the neutral level.

ThresholdParams clear_of_peak(int fixed_level) {
  ThresholdParams params = params_with_fixed(fixed_level);
  params.unimodal = UnimodalPolicy::kClearOfPeak;
  return params;
}

TEST(ClearOfPeak, IsTheDefaultOfCiveAndRawExgOnly) {
  EXPECT_EQ(default_unimodal_policy(VegetationIndex::kCive), UnimodalPolicy::kClearOfPeak);
  EXPECT_EQ(default_unimodal_policy(VegetationIndex::kExgRaw), UnimodalPolicy::kClearOfPeak);
  EXPECT_EQ(default_unimodal_policy(VegetationIndex::kExgNormalized), UnimodalPolicy::kFixedScale);
  EXPECT_EQ(ThresholdParams{}.unimodal, UnimodalPolicy::kIndexDefault);
  for (auto policy : {UnimodalPolicy::kIndexDefault, UnimodalPolicy::kClearOfPeak,
                      UnimodalPolicy::kFixedScale, UnimodalPolicy::kKeepSplit}) {
    EXPECT_EQ(parse_unimodal_policy(to_string(policy)), policy);
  }
  EXPECT_EQ(parse_unimodal_policy("clear_of_peak"), UnimodalPolicy::kClearOfPeak);
  EXPECT_FALSE(parse_unimodal_policy("fixed").has_value());
}

double share_above(const Histogram& histogram, int threshold) {
  return static_cast<double>(histogram_range(histogram, threshold + 1, 255).count) /
         histogram_total(histogram);
}

TEST(ClearOfPeak, SplitThroughTheSoilPeakMovesClearOfIt) {
  Histogram histogram{};
  add_bump(histogram, 127, 2, 97000);  // soil
  add_bump(histogram, 131, 2, 3000);   // a few pale seedlings, inside the soil's flank
  const ThresholdParams params = clear_of_peak(131);
  ASSERT_EQ(histogram_peak(histogram), 127);
  ThresholdParams keep = params;
  keep.unimodal = UnimodalPolicy::kKeepSplit;
  const ThresholdResult split = compute_threshold(histogram, ThresholdMethod::kOtsu, keep);
  ASSERT_FALSE(split.bimodal);
  ASSERT_LT(split.threshold, 130);  // Otsu halves the soil peak
  const ThresholdResult result = compute_threshold(histogram, ThresholdMethod::kOtsu, params);
  EXPECT_FALSE(result.bimodal);
  EXPECT_EQ(result.threshold, 127 + params.peak_margin);
}

TEST(ClearOfPeak, PlausibleSplitIsKept) {
  Histogram histogram{};
  add_bump(histogram, 128, 1.5, 94000);  // soil
  add_bump(histogram, 136, 6, 6000);     // plants, spread over many levels
  const ThresholdParams params = clear_of_peak(131);
  ThresholdParams keep = params;
  keep.unimodal = UnimodalPolicy::kKeepSplit;
  const ThresholdResult split = compute_threshold(histogram, ThresholdMethod::kOtsu, keep);
  ASSERT_FALSE(split.bimodal);
  ASSERT_GE(split.threshold, 128 + params.peak_margin);
  EXPECT_EQ(compute_threshold(histogram, ThresholdMethod::kOtsu, params).threshold,
            split.threshold);
}

TEST(ClearOfPeak, FollowsTheSoilOfEachFrame) {
  // The same seedlings on a soil 4 levels greener (another camera, wet soil): a fixed level
  // would count much of that soil as plant; the answer moves with the soil peak.
  const ThresholdParams params = clear_of_peak(131);
  for (int soil_level : {126, 130}) {
    Histogram histogram{};
    add_bump(histogram, soil_level, 1.5, 99000);
    add_bump(histogram, soil_level + 2, 1.5, 1000);
    const ThresholdResult result = compute_threshold(histogram, ThresholdMethod::kOtsu, params);
    EXPECT_FALSE(result.bimodal) << soil_level;
    EXPECT_EQ(result.threshold, soil_level + params.peak_margin) << soil_level;
    EXPECT_LT(share_above(histogram, result.threshold), 0.03) << soil_level;
  }
}

TEST(ClearOfPeak, BareSoilLeavesFewPixels) {
  // Bare soil as narrow as the field sets' (sigma 1.5 levels): at most its upper 2-sigma tail
  // (2.3 %) is plant.
  Histogram histogram{};
  add_bump(histogram, 127, 1.5, 100000);
  for (ThresholdMethod method : all_threshold_methods()) {
    if (method == ThresholdMethod::kFixed) continue;
    const ThresholdResult result = compute_threshold(histogram, method, clear_of_peak(131));
    EXPECT_FALSE(result.bimodal) << to_string(method);
    EXPECT_LT(share_above(histogram, result.threshold), 0.03) << to_string(method);
  }
}

TEST(ClearOfPeak, GreenPeakIsAFullCanopyOnTheFixedScale) {
  Histogram histogram{};
  add_bump(histogram, 165, 8, 100000);
  for (ThresholdMethod method : all_threshold_methods()) {
    const ThresholdResult result = compute_threshold(histogram, method, clear_of_peak(131));
    EXPECT_EQ(result.threshold, 131) << to_string(method);  // every pixel above: all plants
  }
}

TEST(ClearOfPeak, MarginIsAParameter) {
  Histogram histogram{};
  add_bump(histogram, 127, 2, 100000);
  ThresholdParams params = clear_of_peak(131);
  params.peak_margin = 5;
  EXPECT_EQ(compute_threshold(histogram, ThresholdMethod::kOtsu, params).threshold, 132);
}

}  // namespace
}  // namespace weedspray::vision

namespace weedspray::vision {
namespace {

// Without a resolved fixed level a frame that cannot be split must not become "all plants".
TEST(Thresholds, UnresolvedFixedLevelIsTheSafeSide) {
  Histogram uniform{};
  uniform[200] = 100;
  const ThresholdResult result = compute_threshold(uniform, ThresholdMethod::kOtsu, {});
  EXPECT_EQ(result.threshold, 255);
  EXPECT_FALSE(result.bimodal);
}

}  // namespace
}  // namespace weedspray::vision
