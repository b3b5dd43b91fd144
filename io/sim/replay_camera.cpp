// SPDX-License-Identifier: Apache-2.0
#include "io/sim/replay_camera.hpp"

#include "io/sim/ground_mosaic.hpp"
#include "io/sim/image_file.hpp"

#include <algorithm>
#include <atomic>
#include <filesystem>

namespace weedspray::io::sim {

namespace fs = std::filesystem;
using std::chrono::nanoseconds;

struct ReplayCamera::Impl {
  ReplayCameraConfig config;
  Clock& clock;
  std::vector<fs::path> images;
  bool started = false;
  std::size_t next_index = 0;
  cv::Mat current;
  std::string current_name;
  std::uint64_t sequence = 0;
  nanoseconds next_due{};
  std::string error;
  std::atomic<bool> unplugged{false};
  CameraCounters counters;

  Impl(ReplayCameraConfig c, Clock& k) : config(std::move(c)), clock(k) {}

  // Time until the next frame is due, from the ground speed now (or the fixed rate).
  // Returns false when standing still.
  bool frame_interval(nanoseconds& interval) const {
    double seconds;
    if (config.ground_speed_m_per_s) {
      const double speed = config.ground_speed_m_per_s();
      if (!(speed >= config.min_speed_m_per_s)) return false;
      seconds = config.footprint_length_m / speed;
    } else {
      seconds = 1.0 / config.fps;
    }
    interval = std::chrono::duration_cast<nanoseconds>(std::chrono::duration<double>(seconds));
    return true;
  }

  // Loads the next frame into `current`. Returns kOk, kEnd or kError.
  FrameStatus load_next() {
    if (next_index >= images.size()) {
      if (!config.loop) return FrameStatus::kEnd;
      next_index = 0;
    }
    if (config.source_mm_per_px > 0.0) return lay_next_ground();
    const fs::path& path = images[next_index++];
    std::string failed;
    current = read_bgr_image(path, failed);
    if (current.empty()) {
      error = "replay camera: cannot decode image " + failed;
      return FrameStatus::kError;
    }
    current_name = path.filename().string();
    return FrameStatus::kOk;
  }

  // The frame as the camera sees the ground the next images show.
  FrameStatus lay_next_ground() {
    const GroundScale scale{config.source_mm_per_px, config.frame_mm_per_px,
                            cv::Size(config.frame_width, config.frame_height)};
    std::string failed;
    current = lay_ground(scale, [&]() {
      if (next_index >= images.size()) next_index = 0;
      const fs::path& path = images[next_index++];
      std::string why;
      cv::Mat photo = read_bgr_image(path, why);
      if (photo.empty() && failed.empty()) failed = why;
      current_name = path.filename().string();
      return photo.empty() ? cv::Mat(1, 1, CV_8UC3, cv::Scalar::all(0)) : photo;
    });
    if (!failed.empty()) {
      error = "replay camera: cannot decode image " + failed;
      return FrameStatus::kError;
    }
    return FrameStatus::kOk;
  }
};

ReplayCamera::ReplayCamera(ReplayCameraConfig config, Clock& clock)
    : impl_(std::make_unique<Impl>(std::move(config), clock)) {}

ReplayCamera::~ReplayCamera() = default;

bool ReplayCamera::start() {
  Impl& m = *impl_;
  m.images.clear();
  m.error.clear();
  if (m.config.source_mm_per_px > 0.0 && (!(m.config.frame_mm_per_px > 0.0) ||
                                          m.config.frame_width < 1 || m.config.frame_height < 1)) {
    m.error =
        "replay camera: laying the ground at the camera's scale needs frame_mm_per_px > 0 "
        "and the frame size";
    return false;
  }
  if (!(m.config.footprint_length_m > 0.0) ||
      (!m.config.ground_speed_m_per_s && !(m.config.fps > 0.0))) {
    m.error = "replay camera: footprint_length_m and fps must be > 0";
    return false;
  }
  const fs::path source(m.config.source);
  std::error_code ec;
  if (fs::is_directory(source, ec)) {
    for (const auto& entry : fs::directory_iterator(source, ec))
      if (entry.is_regular_file() && is_readable_image(entry.path()))
        m.images.push_back(entry.path());
    std::sort(m.images.begin(), m.images.end());
    if (m.images.empty()) {
      m.error = "replay camera: no images (*.png, *.jpg, *.jpeg) in directory " + m.config.source;
      return false;
    }
  } else if (fs::is_regular_file(source, ec) && is_readable_image(source)) {
    m.images.push_back(source);
  } else {
    m.error = "replay camera: source " + m.config.source +
              " is neither a directory of images nor a PNG or JPEG file (or does not exist); for a "
              "video, extract its frames first (ffmpeg -i VIDEO DIR/%05d.png)";
    return false;
  }
  m.next_index = 0;
  m.sequence = 0;
  m.next_due = m.clock.now();
  m.started = true;
  return true;
}

void ReplayCamera::set_unplugged(bool unplugged) noexcept {
  impl_->unplugged.store(unplugged);
}

FrameStatus ReplayCamera::next_frame(Frame& frame, std::chrono::milliseconds timeout) {
  Impl& m = *impl_;
  if (!m.started) {
    m.error = "replay camera: next_frame() before start()";
    ++m.counters.errors;
    return FrameStatus::kError;
  }
  const nanoseconds give_up = m.clock.now() + timeout;
  if (m.unplugged.load()) {
    m.clock.sleep_until(give_up);
    ++m.counters.timeouts;
    return FrameStatus::kTimeout;
  }
  // Standing still: no new ground, no new frame; poll the speed until the timeout.
  while (true) {
    nanoseconds interval{};
    if (m.frame_interval(interval)) break;
    const nanoseconds poll = m.clock.now() + std::chrono::milliseconds(10);
    if (poll > give_up) {
      m.clock.sleep_until(give_up);
      ++m.counters.timeouts;
      return FrameStatus::kTimeout;
    }
    m.clock.sleep_until(poll);
    m.next_due = m.clock.now();
  }
  if (m.next_due > give_up) {
    m.clock.sleep_until(give_up);
    ++m.counters.timeouts;
    return FrameStatus::kTimeout;
  }
  m.clock.sleep_until(m.next_due);
  const FrameStatus status = m.load_next();
  if (status == FrameStatus::kError) ++m.counters.errors;
  if (status != FrameStatus::kOk) return status;

  frame.timestamp = m.clock.now();
  frame.sequence = m.sequence++;
  frame.view.data = m.current.data;
  frame.view.width = m.current.cols;
  frame.view.height = m.current.rows;
  frame.view.stride = m.current.step[0];
  frame.view.format = vision::PixelFormat::kBgr24;
  ++m.counters.frames;
  nanoseconds interval{};
  if (!m.frame_interval(interval)) interval = std::chrono::milliseconds(10);
  m.next_due += interval;
  // Fell behind by more than a frame (slow consumer): restart pacing from now.
  if (m.next_due < frame.timestamp) m.next_due = frame.timestamp;
  return FrameStatus::kOk;
}

void ReplayCamera::stop() noexcept {
  impl_->started = false;
}

std::string ReplayCamera::last_error() const {
  return impl_->error;
}

CameraCounters ReplayCamera::counters() const noexcept {
  return impl_->counters;
}

std::size_t ReplayCamera::image_count() const noexcept {
  return impl_->images.size();
}

std::string ReplayCamera::current_source_name() const {
  return impl_->current_name;
}

}  // namespace weedspray::io::sim
