// SPDX-License-Identifier: Apache-2.0
// A Camera replaying recorded field images (a directory of PNG or JPEG files, or one file; read
// by io/sim/image_file.hpp). Frames are paced so consecutive images tile the
// ground: one frame per `footprint_length_m` travelled at the current ground speed (or at a
// fixed `fps` when no speed is given). Timestamps come from the injected clock.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "io/camera.hpp"
#include "io/clock.hpp"

namespace weedspray::io::sim {

struct ReplayCameraConfig {
  // A directory (its *.png / *.jpg / *.jpeg files, sorted by name) or one image file.
  std::string source;
  bool loop = true;
  // Ground distance covered by one image along the direction of travel.
  double footprint_length_m = 1.0;
  // Ground speed [m/s] at the moment a frame is due; empty = use `fps`.
  std::function<double()> ground_speed_m_per_s;
  double fps = 10.0;
  // Speeds below this do not produce frames (standing still: the camera sees the same patch).
  double min_speed_m_per_s = 0.05;
  // Images only: when set (source_mm_per_px > 0), each frame is the ground at the camera's
  // scale, consecutive images resampled and laid edge to edge to fill it (lay_ground; within a
  // frame the list wraps round to its first image); else each image is one frame as it is.
  double source_mm_per_px = 0.0;
  double frame_mm_per_px = 0.0;
  int frame_width = 0;
  int frame_height = 0;
};

class ReplayCamera final : public Camera {
 public:
  ReplayCamera(ReplayCameraConfig config, Clock& clock);
  ~ReplayCamera() override;

  bool start() override;  // lists/opens the source; false with last_error() if nothing usable
  FrameStatus next_frame(Frame& frame, std::chrono::milliseconds timeout) override;
  void stop() noexcept override;
  std::string last_error() const override;
  CameraCounters counters() const noexcept override;

  // Fault injection (any thread): while unplugged, next_frame() delivers nothing and times
  // out, as a camera whose cable came off does.
  void set_unplugged(bool unplugged) noexcept;

  std::size_t image_count() const noexcept;  // images listed (0 for video)
  std::string current_source_name() const;   // file name of the last frame's image

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace weedspray::io::sim
