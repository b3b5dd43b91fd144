// SPDX-License-Identifier: Apache-2.0
// Another board's ground speed and odometer (speed.source = "fleet"), followed on this board's
// clock. The owning board's bridge publishes samples stamped with its daemon's clock; this
// board's bridge hands each to the daemon (FeedSharedMotion), which stamps it with its own
// clock on arrival. The two clocks share no epoch, so a sample's age cannot be read off its
// stamps; what can is how much later than the fastest recent sample it came: the arrival
// minus the sender's stamp is the clocks' offset plus the transit, and its running minimum
// (let rise slowly, so the clocks' drift is followed) is the offset plus the shortest transit.
// Each sample's distance is carried forward by its speed over that extra age and the time
// since it arrived, so the odometer runs on smoothly between samples whatever their jitter.
// Pure: the control loop calls update() every cycle; no allocation, no lock, no clock.
#pragma once

#include <chrono>
#include <cstdint>

#include "daemon/sprayer/shared_fix.hpp"

namespace weedspray::daemon {

// One sample as the daemon received it (trivially copyable: a LatestValue slot).
struct SharedMotionSample {
  double speed_m_per_s = 0;
  double distance_m = 0;               // the owning board's odometer
  std::uint64_t sender_time_ns = 0;    // the owning board's clock when it measured them
  std::chrono::nanoseconds arrival{};  // this board's clock when the sample arrived
  std::uint64_t count = 0;             // samples received so far (0: none yet)
  SharedFix fix;                       // the owning board's fix (mode none: it has none)
};

class SharedMotionTracker {
 public:
  // How fast the clocks' offset estimate may rise (s per s): far above two crystals' drift
  // (1e-4), far below the transit's jitter over the samples of one second.
  static constexpr double kOffsetRise = 1e-3;

  explicit SharedMotionTracker(std::chrono::nanoseconds timeout) noexcept : timeout_(timeout) {}

  // The latest sample and this board's clock now, once a control cycle.
  void update(const SharedMotionSample& latest, std::chrono::nanoseconds now) noexcept;

  // Samples arrive: the latest is within the timeout of now.
  [[nodiscard]] bool fresh() const noexcept { return fresh_; }
  // A sample has ever arrived (a loss before the first is a source not there yet).
  [[nodiscard]] bool had_sample() const noexcept { return had_sample_; }
  [[nodiscard]] double speed_m_per_s() const noexcept { return fresh_ ? speed_m_per_s_ : 0.0; }
  // The owning board's odometer as of now; never runs backwards, held while samples are lost.
  [[nodiscard]] double distance_m() const noexcept { return distance_m_; }
  // How much older than the fastest recent sample the latest one arrived (s).
  [[nodiscard]] double extra_age_s() const noexcept { return extra_age_s_; }
  // The last update() took a new sample (not a repeat of the one before, nor an overtaken one).
  [[nodiscard]] bool took_sample() const noexcept { return took_sample_; }
  // When the owning board's clock read `sender_time_ns`, on this board's clock: its stamp plus
  // the clocks' offset with the shortest transit (the estimate that ages the samples).
  [[nodiscard]] std::chrono::nanoseconds local_time(std::uint64_t sender_time_ns) const noexcept;

 private:
  std::chrono::nanoseconds timeout_;
  std::uint64_t seen_count_ = 0;
  std::uint64_t last_sender_time_ns_ = 0;
  double offset_s_ = 0;  // arrival minus sender stamp, the running minimum
  double last_arrival_s_ = 0;
  double extra_age_s_ = 0;
  double sample_distance_m_ = 0;
  double speed_m_per_s_ = 0;
  std::chrono::nanoseconds sample_arrival_{};
  double distance_m_ = 0;
  bool fresh_ = false;
  bool had_sample_ = false;
  bool took_sample_ = false;
};

}  // namespace weedspray::daemon
