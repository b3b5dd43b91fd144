#include "daemon/sprayer/live_view.hpp"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <exception>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <utility>

#include "vision/overlay.hpp"

namespace weedspray::daemon {

LiveView::LiveView(Sprayer& sprayer, std::vector<int> first_nozzles)
    : sprayer_(sprayer), first_nozzles_(std::move(first_nozzles)) {}

LiveView::~LiveView() {
  cancel("weedsprayd is stopping");
}

CommandResult LiveView::request(std::uint32_t camera, Nanos now, SnapshotReply reply) {
  if (camera >= sprayer_.camera_count()) {
    return {kErrorInvalidArgument, "Snapshot: no camera " + std::to_string(camera) + " (" +
                                       std::to_string(sprayer_.camera_count()) + " configured)"};
  }
  if (pending_) {
    return {kErrorRateLimited, "Snapshot refused: the previous one still waits for its frame"};
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
  SnapshotHandoff& handoff = sprayer_.snapshot(pending_->camera);
  if (const SnapshotHandoff::Capture* capture = handoff.ready()) {
    answer(*capture);
    limit_.mark(now);  // from the answer: encoding is the cost the limit bounds
    handoff.release();
    pending_.reset();
  } else if (now - pending_->asked > kFrameTimeout && handoff.release()) {
    pending_->reply({kErrorUnavailable, "Snapshot: camera " + std::to_string(pending_->camera) +
                                            " delivered no frame within 3 s"},
                    {});
    pending_.reset();
  }
}

void LiveView::cancel(const char* why) {
  if (!pending_) return;
  sprayer_.snapshot(pending_->camera).release();
  pending_->reply({kErrorUnavailable, std::string("Snapshot: ") + why}, {});
  pending_.reset();
}

void LiveView::answer(const SnapshotHandoff::Capture& capture) {
  if (capture.error != nullptr) {
    pending_->reply({kErrorUnavailable, std::string("Snapshot: ") + capture.error}, {});
    return;
  }
  // The duties the nozzles under this camera run now (for ground the camera saw a moment
  // ago: the schedule delays each zone's density until its ground reaches the nozzle).
  const ControlStatus control = sprayer_.control();
  std::vector<double> duties(static_cast<std::size_t>(capture.cols), 0.0);
  for (int col = 0; col < capture.cols; ++col) {
    const int nozzle = first_nozzles_[pending_->camera] + col;
    if (nozzle >= 0 && static_cast<std::uint32_t>(nozzle) < control.nozzles)
      duties[static_cast<std::size_t>(col)] = control.duty_pct[static_cast<std::size_t>(nozzle)];
  }
  try {
    const auto started = std::chrono::steady_clock::now();
    const vision::OverlayZones zones{
        capture.rows, capture.cols,
        std::span<const double>(capture.density.data(),
                                static_cast<std::size_t>(capture.rows * capture.cols)),
        duties};
    vision::BgrImage overlay =
        vision::draw_overlay(capture.frame, capture.classes, capture.region, zones);
    std::vector<std::uint8_t> png;
    // Fastest zlib level: the picture goes over the bus once, and encoding is the cost here.
    cv::imencode(".png", cv::Mat(overlay.height, overlay.width, CV_8UC3, overlay.pixels.data()),
                 png, {cv::IMWRITE_PNG_COMPRESSION, 1});
    spdlog::debug(
        "snapshot of camera {}: {}x{}, {} bytes, {:.1f} ms", pending_->camera, overlay.width,
        overlay.height, png.size(),
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started)
            .count());
    pending_->reply({}, png);
  } catch (const std::exception& error) {
    pending_->reply({kErrorUnavailable, std::string("Snapshot: ") + error.what()}, {});
  }
}

}  // namespace weedspray::daemon
