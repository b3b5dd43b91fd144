// SPDX-License-Identifier: Apache-2.0
// The live view (sprayctl snapshot, D-Bus Snapshot). The main thread takes a request (one at a
// time, and none within half a second of the last answer: at most 2 a second) and asks the
// camera's thread for its next processed frame through its SnapshotHandoff; once that is
// filled, its own encoder thread (normal priority, niced) draws the overlay
// (vision/overlay.hpp) with the nozzles' current duties and encodes the PNG, and the main
// thread replies. No real-time thread does any of it, and the main loop (alarms, state, the
// bus) is not held up by the encoding: 0.1-0.4 s for a 1280x800 field on a loaded core.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "daemon/bus/rate_limit.hpp"
#include "daemon/bus/status.hpp"
#include "daemon/sprayer/sprayer.hpp"

namespace weedspray::daemon {

class LiveView {
 public:
  static constexpr Nanos kMinInterval = std::chrono::milliseconds(500);  // 2 a second
  // A camera that delivers nothing for this long (unplugged; the simulated vehicle standing
  // still) gets the caller an error rather than a hang.
  static constexpr Nanos kFrameTimeout = std::chrono::seconds(3);

  // first_nozzles[i]: camera i's first nozzle (its zone columns are its nozzles in order).
  LiveView(Sprayer& sprayer, std::vector<int> first_nozzles);
  ~LiveView();
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  // Main thread (D-Bus): a refusal at once, or accepted and answered later through `reply`.
  CommandResult request(std::uint32_t camera, Nanos now, SnapshotReply reply);
  // Main thread, every tick: hands a filled capture to the encoder, answers the pending request
  // once its PNG is made, or when no frame came in time.
  void poll(Nanos now);
  // The daemon is stopping (camera threads joined): answers a pending request with `why`.
  void cancel(const char* why);

 private:
  struct Pending {
    std::size_t camera = 0;
    Nanos asked{};
    SnapshotReply reply;
    bool encoding = false;  // its capture is with the encoder thread
  };
  struct Job {  // main -> encoder; the capture stays in its handoff until the answer
    const SnapshotHandoff::Capture* capture = nullptr;
    std::vector<double> duties;
  };
  struct Encoded {  // encoder -> main
    CommandResult result;
    std::vector<std::uint8_t> png;
  };

  std::vector<double> current_duties(std::size_t camera, int cols) const;
  void encoder_loop(std::stop_token stop);
  void finish(Nanos now, const CommandResult& result, std::span<const std::uint8_t> png);

  Sprayer& sprayer_;
  std::vector<int> first_nozzles_;
  RateLimit limit_{kMinInterval};
  std::optional<Pending> pending_;
  std::mutex mutex_;  // guards job_ and encoded_ (main thread and encoder only)
  std::condition_variable_any wake_;
  std::optional<Job> job_;
  std::optional<Encoded> encoded_;
  std::jthread encoder_;  // last: stopped and joined first
};

}  // namespace weedspray::daemon
