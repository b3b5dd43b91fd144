// The live view (sprayctl snapshot, D-Bus Snapshot): on the main thread, takes a request (one
// at a time, and none within half a second of the last answer: at most 2 a second), asks the
// camera's thread for its next processed frame through its SnapshotHandoff, and once that is filled
// draws the overlay (vision/overlay.hpp) with the nozzles' current duties and encodes the PNG - all
// off the real-time threads.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
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

  CommandResult request(std::uint32_t camera, Nanos now, SnapshotReply reply);
  // Every main-loop tick: answers the pending request once its frame is there or timed out.
  void poll(Nanos now);
  // The daemon is stopping (camera threads joined): answer a pending request with `why`.
  void cancel(const char* why);

 private:
  struct Pending {
    std::size_t camera = 0;
    Nanos asked{};
    SnapshotReply reply;
  };
  void answer(const SnapshotHandoff::Capture& capture);

  Sprayer& sprayer_;
  std::vector<int> first_nozzles_;
  RateLimit limit_{kMinInterval};
  std::optional<Pending> pending_;
};

}  // namespace weedspray::daemon
