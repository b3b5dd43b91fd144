// SPDX-License-Identifier: Apache-2.0
// Automatic thresholds on the 256-bin histogram of an 8-bit vegetation index.
// Convention everywhere: a pixel is vegetation when its index value is > threshold.
//
// Degenerate histograms (empty, one level, all black, all saturated) return bimodal = false
// and ThresholdParams::fixed_threshold, so the frame is classified as a whole by where its
// values sit on the fixed index scale. Histograms that are not degenerate but do not look
// bimodal are answered by ThresholdParams::unimodal (default: keep the method's split unless
// it cuts the soil peak).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "vision/histogram.hpp"
#include "vision/vegetation_index.hpp"

namespace weedspray::vision {

enum class ThresholdMethod : std::uint8_t {
  kFit,     // fast iterative: from the mean, t = (mean below + mean above) / 2 until |dt| < 0.5
  kOtsu,    // maximum between-class variance (the reference for the error metrics)
  kKmeans,  // two-cluster K-means on the histogram
  kHbt,     // valley between the two main peaks of the smoothed histogram
  kPso,     // particle swarm on Otsu's between-class variance, full range (2018 baseline)
  kIpso,    // the 2018 paper's improved PSO (narrowed range, scaled swarm, local search)
  kFixed,   // ThresholdParams::fixed_threshold on the fixed index scale
};

// Config names: "fit", "otsu", "kmeans", "hbt", "pso", "ipso", "fixed".
std::string_view to_string(ThresholdMethod method);
std::optional<ThresholdMethod> parse_threshold_method(std::string_view name);
std::span<const ThresholdMethod> all_threshold_methods();
std::span<const std::string_view> threshold_method_names();

// What a method's answer becomes when the histogram does not look bimodal.
enum class UnimodalPolicy : std::uint8_t {
  // The Pipeline puts the index's own policy (default_unimodal_policy). Left unresolved,
  // compute_threshold uses kFixedScale.
  kIndexDefault,
  // Keep Otsu's split (whatever the method) unless it is implausible, judged from the frame's
  // own histogram peak p (the dominant colour): if p is green on the index scale (p >
  // fixed_threshold + peak_margin) the frame is mostly plants and fixed_threshold judges it;
  // if the split lies below p + peak_margin it cuts the soil peak or calls it plant, so the
  // answer is p + peak_margin, the first level clear of the soil. A fixed level picked on one
  // camera sits inside another camera's soil peak; the soil peak moves with the frame.
  kClearOfPeak,
  kFixedScale,  // use fixed_threshold: the frame is judged on the fixed index scale
  kKeepSplit,   // keep the method's own split (the papers' behaviour; splits bare soil)
};

// Config names: "index_default", "clear_of_peak", "fixed_scale", "keep_split".
std::string_view to_string(UnimodalPolicy policy);
std::optional<UnimodalPolicy> parse_unimodal_policy(std::string_view name);

// The policy measured best for an index on both bundled field sets (ews-train wheat, peanut;
// weedspray-lab vision-eval): kClearOfPeak for CIVE and raw ExG, whose soil is a narrow peak
// near the neutral level; kFixedScale for the others, where Otsu's unimodal split often lands
// in the far tail above the plants (normalised ExG, ExG-ExR on the peanut photos).
UnimodalPolicy default_unimodal_policy(VegetationIndex index);

struct ThresholdParams {
  UnimodalPolicy unimodal = UnimodalPolicy::kIndexDefault;
  // kClearOfPeak: levels above the histogram peak that still belong to the soil. Chosen by
  // cross-validation over the two bundled sets (weedspray-lab vision-eval; README): picked on
  // ews-train (wheat) it also beats both other policies on peanut (another crop and camera).
  int peak_margin = 3;
  // Bimodality test at the chosen threshold t: each class holds at least min_class_share of
  // the pixels, and Otsu's separability sigma_between^2 / sigma_total^2 >= min_separability
  // (a single Gaussian split at its mean gives 2/pi = 0.637; two clean modes approach 1).
  // The class means must also lie min_mean_gap levels apart: a split of soil texture or
  // sensor noise (a few levels) is never two classes, however clean.
  double min_class_share = 0.001;
  double min_separability = 0.65;
  double min_mean_gap = 5.0;
  // Level on the index scale used by kFixed and as the answer for unimodal/degenerate frames.
  // kIndexDefault: the Pipeline puts the index's own level (default_fixed_threshold). Left
  // unresolved, compute_threshold uses 255 (nothing is vegetation): a frame that cannot be
  // judged must not open valves.
  static constexpr int kIndexDefault = -1;
  int fixed_threshold = kIndexDefault;
  // PSO / IPSO (2018 paper): M particles, iterations, c1 = c2, inertia from w_max to w_min.
  int pso_particles = 15;
  int pso_iterations = 30;
  double pso_c1 = 2.0;
  double pso_c2 = 2.0;
  double pso_w_max = 0.8;
  double pso_w_min = 0.4;
  int ipso_local_radius = 2;   // P: exhaustive search within +-P levels of the best particle
  std::uint64_t seed = 12345;  // PSO random stream; the same seed gives the same threshold
};

struct ThresholdResult {
  int threshold = 0;  // vegetation is value > threshold; 0..255
  bool bimodal = false;
};

ThresholdResult compute_threshold(const Histogram& histogram, ThresholdMethod method,
                                  const ThresholdParams& params = {});

// The bimodality test above at threshold t (see ThresholdParams).
bool looks_bimodal(const Histogram& histogram, int t, const ThresholdParams& params);

// Otsu's between-class variance of splitting at t (class 0 = values <= t); 0 if a class is
// empty. Exposed for tests and the PSO fitness.
double between_class_variance(const Histogram& histogram, int t);

}  // namespace weedspray::vision
