// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/live_view.hpp"

#include <pthread.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <exception>
#include <string>
#include <utility>

namespace weedspray::daemon {
LiveView::LiveView(Sprayer& sprayer, std::vector<int> first_nozzles)
    : sprayer_(sprayer),
      first_nozzles_(std::move(first_nozzles)),
      encoder_([this](std::stop_token stop) { encoder_loop(stop); }) {}

LiveView::~LiveView() {
  cancel("weedsprayd is stopping");
}

CommandResult LiveView::request(std::uint32_t camera, Nanos now, SnapshotReply reply) {
  if (camera >= sprayer_.camera_count()) {
    return {kErrorInvalidArgument, "Snapshot: no camera " + std::to_string(camera) + " (" +
                                       std::to_string(sprayer_.camera_count()) + " configured)"};
  }
  if (pending_) {
    return {kErrorRateLimited, "Snapshot refused: the previous one is not answered yet"};
  }
  const CameraStatus status = sprayer_.camera(camera);
  if (status.frames == 0 || status.frame_bytes == 0) {
    return {kErrorUnavailable,
            "Snapshot: camera " + std::to_string(camera) + " has delivered no frame yet"};
  }
  Nanos wait{};
  if (!limit_.allowed(now, wait)) {
    char message[120];
    std::snprintf(message, sizeof message,
                  "Snapshot refused: at most 2 a second; try again in %.2f s",
                  std::chrono::duration<double>(wait).count());
    return {kErrorRateLimited, message};
  }
  if (!sprayer_.snapshot(camera).request(status.frame_bytes, status.class_map_pixels)) {
    return {kErrorRateLimited, "Snapshot refused: the camera's handoff is busy"};
  }
  pending_ = Pending{camera, now, std::move(reply)};
  return {};
}

void LiveView::poll(Nanos now) {
  if (!pending_) return;
  if (pending_->encoding) {
    std::optional<Encoded> encoded;
    {
      const std::lock_guard lock(mutex_);
      encoded.swap(encoded_);
    }
    if (encoded) finish(now, encoded->result, encoded->png);
    return;
  }
  SnapshotHandoff& handoff = sprayer_.snapshot(pending_->camera);
  if (const SnapshotHandoff::Capture* capture = handoff.ready()) {
    if (capture->error != nullptr) {
      finish(now, {kErrorUnavailable, std::string("Snapshot: ") + capture->error}, {});
      return;
    }
    {
      const std::lock_guard lock(mutex_);
      job_ = Job{capture, current_duties(pending_->camera, capture->cols)};
    }
    pending_->encoding = true;
    wake_.notify_one();
  } else if (now - pending_->asked > kFrameTimeout && handoff.release()) {
    pending_->reply({kErrorUnavailable, "Snapshot: camera " + std::to_string(pending_->camera) +
                                            " delivered no frame within 3 s"},
                    {});
    pending_.reset();
  }
}

void LiveView::finish(Nanos now, const CommandResult& result, std::span<const std::uint8_t> png) {
  sprayer_.snapshot(pending_->camera).release();
  pending_->reply(result, png);
  pending_.reset();
  limit_.mark(now);  // from the answer: encoding is the cost the limit bounds
}

void LiveView::cancel(const char* why) {
  if (!pending_) return;
  if (pending_->encoding) {
    // The encoder reads the capture: let it finish before the handoff takes it back.
    encoder_.request_stop();
    wake_.notify_one();
    if (encoder_.joinable()) encoder_.join();
  }
  sprayer_.snapshot(pending_->camera).release();
  pending_->reply({kErrorUnavailable, std::string("Snapshot: ") + why}, {});
  pending_.reset();
}

// The duties the nozzles under this camera run now (for ground the camera saw a moment ago:
// the schedule delays each zone's density until its ground reaches the nozzle).
std::vector<double> LiveView::current_duties(std::size_t camera, int cols) const {
  const ControlStatus control = sprayer_.control();
  std::vector<double> duties(static_cast<std::size_t>(cols), 0.0);
  for (int col = 0; col < cols; ++col) {
    const int nozzle = first_nozzles_[camera] + col;
    if (nozzle >= 0 && static_cast<std::uint32_t>(nozzle) < control.nozzles)
      duties[static_cast<std::size_t>(col)] = control.duty_pct[static_cast<std::size_t>(nozzle)];
  }
  return duties;
}

void LiveView::encoder_loop(std::stop_token stop) {
  pthread_setname_np(pthread_self(), "ws-liveview");
  // Below the camera threads: a snapshot must not cost the vision its frames.
  setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), 10);
  while (true) {
    Job job;
    {
      std::unique_lock lock(mutex_);
      if (!wake_.wait(lock, stop, [this] { return job_.has_value(); })) return;
      job = std::move(*job_);
      job_.reset();
    }
    Encoded encoded;
    const auto started = std::chrono::steady_clock::now();
    try {
      encoded.png = overlay_png(*job.capture, job.duties);
      spdlog::debug(
          "snapshot: {}x{}, {} bytes, overlay + PNG {:.1f} ms", job.capture->frame.width,
          job.capture->frame.height, encoded.png.size(),
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started)
              .count());
    } catch (const std::exception& error) {
      encoded.result = {kErrorUnavailable, std::string("Snapshot: ") + error.what()};
      encoded.png.clear();
    }
    const std::lock_guard lock(mutex_);
    encoded_ = std::move(encoded);
  }
}

}  // namespace weedspray::daemon
