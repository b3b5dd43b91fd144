// SPDX-License-Identifier: Apache-2.0
// One camera's latest frame, class map and zone densities, handed from its camera thread to
// the main thread only when a live-view snapshot is asked for (sprayctl snapshot). The main
// thread sizes the buffers before it asks, so the camera thread only copies into them: no
// allocation, lock or system call there, and one relaxed atomic load per frame when nobody asks.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "vision/image_view.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::daemon {

class SnapshotHandoff {
 public:
  struct Capture {
    vision::ImageView frame;    // over frame_bytes, packed rows
    vision::ImageView classes;  // over class_bytes (Pipeline::class_map_into)
    vision::PixelRect region{};
    int rows = 0;
    int cols = 0;
    std::array<double, vision::kMaxZones> density{};  // weed density, as the frame gave it
    std::chrono::nanoseconds capture_time{};
    const char* error = nullptr;  // set (a literal) when the frame could not be handed over
  };

  // Main thread: makes room for a frame of `frame_bytes` (packed) and a class map of
  // `class_pixels` (allocating only when they grow) and asks for the camera's next processed
  // frame. False while an earlier request is outstanding.
  bool request(std::size_t frame_bytes, std::size_t class_pixels);
  // Main thread: the capture once the camera thread has filled it, else nullptr.
  const Capture* ready() const noexcept;
  // Main thread: done with the capture, or no longer waiting for one. False only while the
  // camera thread is filling it at this moment (call again: the copy takes milliseconds).
  bool release() noexcept;

  // Camera thread, after each processed frame.
  bool wanted() const noexcept { return state_.load(std::memory_order_relaxed) == kRequested; }
  void fill(const vision::ImageView& frame, std::chrono::nanoseconds capture_time,
            vision::Pipeline& pipeline, const vision::FrameResult& result) noexcept;

  // Bytes a frame takes packed (3 per pixel for BGR/RGB, 2 for YUYV, 1 for grey).
  static std::size_t packed_bytes(const vision::ImageView& frame) noexcept;

 private:
  enum State : int { kIdle, kRequested, kFilling, kReady };
  std::atomic<int> state_{kIdle};
  Capture capture_;
  std::vector<std::uint8_t> frame_bytes_;
  std::vector<std::uint8_t> class_bytes_;
};

// A filled capture as the live view's PNG: the overlay (vision/overlay.hpp) with `duties`, one
// per zone column, written in. Throws std::invalid_argument / std::runtime_error. Slow (0.1 s
// and more for 1280x800): never on a real-time thread.
std::vector<std::uint8_t> overlay_png(const SnapshotHandoff::Capture& capture,
                                      std::span<const double> duties);

}  // namespace weedspray::daemon
