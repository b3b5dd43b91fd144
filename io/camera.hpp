// SPDX-License-Identifier: Apache-2.0
// A frame source: V4L2 on the board (hw::V4l2Camera), recorded images/video in simulation
// (sim::ReplayCamera). Errors after start() are reported through next_frame()'s result and the
// counters, never thrown.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "vision/image_view.hpp"

namespace weedspray::io {

struct Frame {
  vision::ImageView view;                // valid until the next next_frame() or stop()
  std::chrono::nanoseconds timestamp{};  // capture time on the CLOCK_MONOTONIC time line
  std::uint64_t sequence = 0;            // frame counter from the source (gaps = dropped)
};

enum class FrameStatus {
  kOk,       // `frame` holds a new frame
  kTimeout,  // nothing within the timeout; try again
  kError,    // a device error; the camera is recovering (see last_error()); try again
  kEnd,      // the source is exhausted (replay without looping); stop
};

struct CameraCounters {
  std::uint64_t frames = 0;
  std::uint64_t timeouts = 0;
  std::uint64_t errors = 0;
  std::uint64_t reopens = 0;  // successful recoveries after the device vanished
  std::uint64_t dropped = 0;  // gaps in the sequence numbers
};

class Camera {
 public:
  virtual ~Camera() = default;
  // Opens and configures the device and starts streaming. Returns false with last_error() set.
  virtual bool start() = 0;
  virtual FrameStatus next_frame(Frame& frame, std::chrono::milliseconds timeout) = 0;
  virtual void stop() noexcept = 0;
  virtual std::string last_error() const = 0;
  virtual CameraCounters counters() const noexcept = 0;
};

}  // namespace weedspray::io
