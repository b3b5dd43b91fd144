// SPDX-License-Identifier: Apache-2.0
#include "vision/threshold.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace weedspray::vision {
namespace {

constexpr std::array kMethods = {
    ThresholdMethod::kFit, ThresholdMethod::kOtsu, ThresholdMethod::kKmeans, ThresholdMethod::kHbt,
    ThresholdMethod::kPso, ThresholdMethod::kIpso, ThresholdMethod::kFixed,
};
constexpr std::array<std::string_view, kMethods.size()> kMethodNames = {
    "fit", "otsu", "kmeans", "hbt", "pso", "ipso", "fixed",
};

// In UnimodalPolicy's order.
constexpr std::array<std::string_view, 4> kPolicyNames = {
    "index_default",
    "clear_of_peak",
    "fixed_scale",
    "keep_split",
};

struct Extent {
  int min_level = 0;
  int max_level = 0;
};

Extent occupied_extent(const Histogram& histogram) {
  Extent extent{255, 0};
  for (int level = 0; level < 256; ++level) {
    if (histogram[level] != 0) {
      extent.min_level = std::min(extent.min_level, level);
      extent.max_level = std::max(extent.max_level, level);
    }
  }
  return extent;
}

int clamp_level(double t) {
  return std::clamp(static_cast<int>(std::floor(t)), 0, 255);
}

// FIT: Ridler-Calvard iteration from the global mean (UGV paper).
int fit_threshold(const Histogram& histogram) {
  double t = histogram_range(histogram, 0, 255).mean();
  for (int iteration = 0; iteration < 256; ++iteration) {
    const int split = clamp_level(t);
    const HistogramRange below = histogram_range(histogram, 0, split);
    const HistogramRange above = histogram_range(histogram, split + 1, 255);
    if (below.count == 0 || above.count == 0) break;
    const double next = (below.mean() + above.mean()) / 2.0;
    const bool converged = std::abs(next - t) < 0.5;
    t = next;
    if (converged) break;
  }
  return clamp_level(t);
}

// One pass with running sums (between_class_variance per level would be 256 x 256).
int otsu_threshold(const Histogram& histogram) {
  const HistogramRange all = histogram_range(histogram, 0, 255);
  const double total = static_cast<double>(all.count);
  std::uint64_t count_below = 0;
  std::uint64_t sum_below = 0;
  int best = 0;
  double best_variance = -1.0;
  for (int t = 0; t < 255; ++t) {
    count_below += histogram[t];
    sum_below += static_cast<std::uint64_t>(histogram[t]) * t;
    const std::uint64_t count_above = all.count - count_below;
    if (count_below == 0 || count_above == 0) continue;
    const double difference = static_cast<double>(sum_below) / count_below -
                              static_cast<double>(all.sum - sum_below) / count_above;
    const double variance = (count_below / total) * (count_above / total) * difference * difference;
    if (variance > best_variance) {
      best_variance = variance;
      best = t;
    }
  }
  return best;
}

// Two-cluster K-means on the grey levels, weighted by the histogram.
int kmeans_threshold(const Histogram& histogram, Extent extent) {
  double low = extent.min_level;
  double high = extent.max_level;
  for (int iteration = 0; iteration < 256; ++iteration) {
    const int split = clamp_level((low + high) / 2.0);
    const HistogramRange below = histogram_range(histogram, 0, split);
    const HistogramRange above = histogram_range(histogram, split + 1, 255);
    if (below.count == 0 || above.count == 0) break;
    const double next_low = below.mean();
    const double next_high = above.mean();
    const bool converged = next_low == low && next_high == high;
    low = next_low;
    high = next_high;
    if (converged) break;
  }
  return clamp_level((low + high) / 2.0);
}

// HBT (Prewitt-Mendelsohn): smooth with a 3-level mean until at most two peaks remain; the
// threshold is the lowest point between them. nullopt if the histogram never shows two.
std::optional<int> hbt_threshold(const Histogram& histogram) {
  std::array<double, 256> smooth{};
  std::array<double, 256> next{};
  for (int i = 0; i < 256; ++i) smooth[i] = histogram[i];
  for (int iteration = 0; iteration < 10000; ++iteration) {
    std::array<int, 2> peaks{};
    int peak_count = 0;
    for (int i = 1; i < 255; ++i) {
      if (smooth[i - 1] < smooth[i] && smooth[i] >= smooth[i + 1]) {
        if (peak_count < 2) peaks[peak_count] = i;
        ++peak_count;
      }
    }
    if (peak_count == 2) {
      const auto valley = std::min_element(smooth.begin() + peaks[0], smooth.begin() + peaks[1]);
      return static_cast<int>(valley - smooth.begin());
    }
    if (peak_count < 2) return std::nullopt;
    for (int i = 0; i < 256; ++i) {
      next[i] = (smooth[std::max(i - 1, 0)] + smooth[i] + smooth[std::min(i + 1, 255)]) / 3.0;
    }
    smooth = next;
  }
  return std::nullopt;
}

// SplitMix64: a tiny, fully specified generator, so a seed gives the same swarm on every
// standard library (std:: distributions are implementation-defined).
class SeededRandom {
 public:
  explicit SeededRandom(std::uint64_t seed) : state_(seed) {}
  double uniform() {  // [0, 1)
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  }

 private:
  std::uint64_t state_;
};

constexpr int kMaxParticles = 64;

// Particle swarm maximising Otsu's between-class variance over thresholds in [low, high].
int particle_swarm(const Histogram& histogram, double low, double high, int particles,
                   const ThresholdParams& params) {
  particles = std::clamp(particles, 1, kMaxParticles);
  SeededRandom random(params.seed);
  std::array<double, kMaxParticles> position{}, velocity{}, best_position{}, best_fitness{};
  const double span = std::max(high - low, 1.0);
  const double max_speed = span / 4.0;
  auto fitness = [&](double x) {
    return between_class_variance(histogram, std::clamp(static_cast<int>(std::lround(x)), 0, 255));
  };
  double global_position = low;
  double global_fitness = -1.0;
  for (int i = 0; i < particles; ++i) {
    position[i] = low + random.uniform() * span;
    velocity[i] = (random.uniform() * 2.0 - 1.0) * max_speed;
    best_position[i] = position[i];
    best_fitness[i] = fitness(position[i]);
    if (best_fitness[i] > global_fitness) {
      global_fitness = best_fitness[i];
      global_position = position[i];
    }
  }
  const int iterations = std::max(params.pso_iterations, 1);
  for (int iteration = 0; iteration < iterations; ++iteration) {
    const double inertia = params.pso_w_max - (params.pso_w_max - params.pso_w_min) * iteration /
                                                  std::max(iterations - 1, 1);
    bool collapsed = true;
    for (int i = 0; i < particles; ++i) {
      velocity[i] = inertia * velocity[i] +
                    params.pso_c1 * random.uniform() * (best_position[i] - position[i]) +
                    params.pso_c2 * random.uniform() * (global_position - position[i]);
      velocity[i] = std::clamp(velocity[i], -max_speed, max_speed);
      position[i] = std::clamp(position[i] + velocity[i], low, high);
      const double value = fitness(position[i]);
      if (value > best_fitness[i]) {
        best_fitness[i] = value;
        best_position[i] = position[i];
      }
      if (value > global_fitness) {
        global_fitness = value;
        global_position = position[i];
      }
      collapsed = collapsed && std::abs(position[i] - global_position) < 0.5;
    }
    if (collapsed) break;  // the swarm has met: further iterations cannot move it
  }
  return std::clamp(static_cast<int>(std::lround(global_position)), 0, 255);
}

int pso_threshold(const Histogram& histogram, Extent extent, const ThresholdParams& params) {
  return particle_swarm(histogram, extent.min_level, extent.max_level, params.pso_particles,
                        params);
}

// IPSO (2018 paper, steps 1-10): the swarm searches [mean of the darker half, mean of the
// brighter half] split at the global mean, with the swarm size scaled by the width of that
// range relative to the occupied grey range (the paper's G_f = (mu_B - mu_A) / L * G_s), then
// an exhaustive search within +-P levels of the best particle.
int ipso_threshold(const Histogram& histogram, Extent extent, const ThresholdParams& params) {
  const double global_mean = histogram_range(histogram, 0, 255).mean();
  const int split = clamp_level(global_mean);
  const double mean_a = histogram_range(histogram, 0, split).mean();
  const HistogramRange upper = histogram_range(histogram, split + 1, 255);
  const double mean_b = upper.count == 0 ? extent.max_level : upper.mean();
  const double grey_range = std::max(extent.max_level - extent.min_level, 1);
  const int swarm = std::max(
      3, static_cast<int>(std::lround(params.pso_particles * (mean_b - mean_a) / grey_range)));
  int best = particle_swarm(histogram, mean_a, mean_b, swarm, params);
  double best_variance = between_class_variance(histogram, best);
  const int centre = best;
  for (int t = std::max(centre - params.ipso_local_radius, 0);
       t <= std::min(centre + params.ipso_local_radius, 255); ++t) {
    const double variance = between_class_variance(histogram, t);
    if (variance > best_variance) {
      best_variance = variance;
      best = t;
    }
  }
  return best;
}

// UnimodalPolicy::kClearOfPeak (see threshold.hpp).
int clear_of_peak(const Histogram& histogram, int otsu, int fixed, int margin) {
  const int peak = histogram_peak(histogram);
  if (peak > fixed + margin) return fixed;  // the dominant colour is green: mostly plants
  return std::max(otsu, std::min(peak + margin, 255));
}

}  // namespace

std::string_view to_string(ThresholdMethod method) {
  return kMethodNames[static_cast<std::size_t>(method)];
}

std::optional<ThresholdMethod> parse_threshold_method(std::string_view name) {
  for (std::size_t i = 0; i < kMethods.size(); ++i) {
    if (kMethodNames[i] == name) return kMethods[i];
  }
  return std::nullopt;
}

std::span<const ThresholdMethod> all_threshold_methods() {
  return kMethods;
}
std::span<const std::string_view> threshold_method_names() {
  return kMethodNames;
}

std::string_view to_string(UnimodalPolicy policy) {
  return kPolicyNames[static_cast<std::size_t>(policy)];
}

std::optional<UnimodalPolicy> parse_unimodal_policy(std::string_view name) {
  for (std::size_t i = 0; i < kPolicyNames.size(); ++i) {
    if (kPolicyNames[i] == name) return static_cast<UnimodalPolicy>(i);
  }
  return std::nullopt;
}

UnimodalPolicy default_unimodal_policy(VegetationIndex index) {
  switch (index) {
    case VegetationIndex::kCive:
    case VegetationIndex::kExgRaw:
      return UnimodalPolicy::kClearOfPeak;
    default:
      return UnimodalPolicy::kFixedScale;
  }
}

double between_class_variance(const Histogram& histogram, int t) {
  const HistogramRange below = histogram_range(histogram, 0, t);
  const HistogramRange above = histogram_range(histogram, t + 1, 255);
  if (below.count == 0 || above.count == 0) return 0.0;
  const double total = static_cast<double>(below.count + above.count);
  const double w0 = below.count / total;
  const double w1 = above.count / total;
  const double difference = below.mean() - above.mean();
  return w0 * w1 * difference * difference;
}

bool looks_bimodal(const Histogram& histogram, int t, const ThresholdParams& params) {
  const HistogramRange all = histogram_range(histogram, 0, 255);
  const HistogramRange below = histogram_range(histogram, 0, t);
  const HistogramRange above = histogram_range(histogram, t + 1, 255);
  if (all.count == 0) return false;
  const double total = static_cast<double>(all.count);
  if (below.count < params.min_class_share * total ||
      above.count < params.min_class_share * total) {
    return false;
  }
  if (above.mean() - below.mean() < params.min_mean_gap) return false;
  double total_variance = 0.0;
  const double mean = all.mean();
  for (int level = 0; level < 256; ++level) {
    total_variance += histogram[level] * (level - mean) * (level - mean);
  }
  total_variance /= total;
  if (total_variance <= 0.0) return false;
  return between_class_variance(histogram, t) / total_variance >= params.min_separability;
}

ThresholdResult compute_threshold(const Histogram& histogram, ThresholdMethod method,
                                  const ThresholdParams& params) {
  const int fixed = params.fixed_threshold == ThresholdParams::kIndexDefault
                        ? 255
                        : std::clamp(params.fixed_threshold, 0, 255);
  const Extent extent = occupied_extent(histogram);
  // Empty or single-level frames (black, saturated, uniform): nothing to split.
  if (histogram_total(histogram) == 0 || extent.max_level <= extent.min_level) {
    return {fixed, false};
  }
  std::optional<int> split;
  switch (method) {
    case ThresholdMethod::kFit:
      split = fit_threshold(histogram);
      break;
    case ThresholdMethod::kOtsu:
      split = otsu_threshold(histogram);
      break;
    case ThresholdMethod::kKmeans:
      split = kmeans_threshold(histogram, extent);
      break;
    case ThresholdMethod::kHbt:
      split = hbt_threshold(histogram);
      break;
    case ThresholdMethod::kPso:
      split = pso_threshold(histogram, extent, params);
      break;
    case ThresholdMethod::kIpso:
      split = ipso_threshold(histogram, extent, params);
      break;
    case ThresholdMethod::kFixed:
      return {fixed, looks_bimodal(histogram, fixed, params)};
  }
  const bool bimodal = split.has_value() && looks_bimodal(histogram, *split, params);
  if (bimodal) return {*split, true};
  switch (params.unimodal) {
    case UnimodalPolicy::kClearOfPeak: {
      // Only Otsu's split is judged: other methods' splits of a unimodal histogram are not
      // comparable (HBT's valley can lie in the far tail, above every plant).
      const int otsu = method == ThresholdMethod::kOtsu ? *split : otsu_threshold(histogram);
      return {clear_of_peak(histogram, otsu, fixed, params.peak_margin), false};
    }
    case UnimodalPolicy::kKeepSplit:
      return {split.value_or(fixed), false};
    case UnimodalPolicy::kIndexDefault:
    case UnimodalPolicy::kFixedScale:
      break;
  }
  return {fixed, false};
}

}  // namespace weedspray::vision
