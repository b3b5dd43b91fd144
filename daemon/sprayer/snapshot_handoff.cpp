// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/snapshot_handoff.hpp"

#include <cstring>

#include "vision/overlay.hpp"

namespace weedspray::daemon {

std::size_t SnapshotHandoff::packed_bytes(const vision::ImageView& frame) noexcept {
  std::size_t per_pixel = 3;
  if (frame.format == vision::PixelFormat::kYuyv) per_pixel = 2;
  if (frame.format == vision::PixelFormat::kGrey) per_pixel = 1;
  return static_cast<std::size_t>(frame.width) * frame.height * per_pixel;
}

bool SnapshotHandoff::request(std::size_t frame_bytes, std::size_t class_pixels) {
  if (state_.load(std::memory_order_acquire) != kIdle) return false;
  // Idle: the camera thread does not touch the buffers.
  if (frame_bytes_.size() < frame_bytes) frame_bytes_.resize(frame_bytes);
  if (class_bytes_.size() < class_pixels) class_bytes_.resize(class_pixels);
  state_.store(kRequested, std::memory_order_release);
  return true;
}

const SnapshotHandoff::Capture* SnapshotHandoff::ready() const noexcept {
  return state_.load(std::memory_order_acquire) == kReady ? &capture_ : nullptr;
}

bool SnapshotHandoff::release() noexcept {
  int expected = kRequested;
  if (state_.compare_exchange_strong(expected, kIdle, std::memory_order_acq_rel)) return true;
  if (expected == kFilling) return false;
  state_.store(kIdle, std::memory_order_release);  // kReady or already kIdle
  return true;
}

void SnapshotHandoff::fill(const vision::ImageView& frame, std::chrono::nanoseconds capture_time,
                           vision::Pipeline& pipeline, const vision::FrameResult& result) noexcept {
  int expected = kRequested;
  // The main thread may have given up on the request meanwhile.
  if (!state_.compare_exchange_strong(expected, kFilling, std::memory_order_acq_rel)) return;
  Capture& c = capture_;
  c = Capture{};
  c.capture_time = capture_time;
  c.rows = result.rows;
  c.cols = result.cols;
  c.density = result.zone_density;
  c.region = pipeline.region();
  const std::size_t row_bytes = packed_bytes(frame) / (frame.height > 0 ? frame.height : 1);
  if (!pipeline.last_frame_ok() || frame.data == nullptr) {
    c.error = "the vision pipeline could not use the latest frame";
  } else if (packed_bytes(frame) > frame_bytes_.size()) {
    c.error = "the frame grew after the request (camera size changed): ask again";
  } else {
    for (int y = 0; y < frame.height; ++y) {
      std::memcpy(frame_bytes_.data() + y * row_bytes, frame.data + y * frame.stride, row_bytes);
    }
    c.frame = {frame_bytes_.data(), frame.width, frame.height, row_bytes, frame.format};
    c.classes = pipeline.class_map_into(class_bytes_);
    if (c.classes.data == nullptr) c.error = "the class map grew after the request: ask again";
  }
  state_.store(kReady, std::memory_order_release);
}

std::vector<std::uint8_t> overlay_png(const SnapshotHandoff::Capture& capture,
                                      std::span<const double> duties) {
  const vision::OverlayZones zones{
      capture.rows, capture.cols,
      std::span<const double>(capture.density.data(),
                              static_cast<std::size_t>(capture.rows * capture.cols)),
      duties};
  return vision::encode_png(
      vision::draw_overlay(capture.frame, capture.classes, capture.region, zones));
}

}  // namespace weedspray::daemon
