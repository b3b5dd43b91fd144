// SPDX-License-Identifier: Apache-2.0
#include "io/linux/v4l2_camera.hpp"

#include "io/linux/mjpeg_decoder.hpp"

#include <fcntl.h>
#include <libv4l2.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/mman.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <vector>

namespace weedspray::io::hw {

using std::chrono::milliseconds;
using std::chrono::nanoseconds;

CameraPixelFormat parse_camera_pixel_format(const std::string& text) {
  std::string t = text;
  std::transform(t.begin(), t.end(), t.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (t == "yuyv") return CameraPixelFormat::kYuyv;
  if (t == "mjpeg" || t == "mjpg") return CameraPixelFormat::kMjpeg;
  if (t == "rgb24" || t == "rgb") return CameraPixelFormat::kRgb24;
  if (t == "grey" || t == "gray") return CameraPixelFormat::kGrey;
  throw std::invalid_argument("camera pixel format '" + text +
                              "' is not one of yuyv, mjpeg, rgb24, grey");
}

namespace {

std::uint32_t fourcc_of(CameraPixelFormat f) {
  switch (f) {
    case CameraPixelFormat::kYuyv:
      return V4L2_PIX_FMT_YUYV;
    case CameraPixelFormat::kMjpeg:
      return V4L2_PIX_FMT_MJPEG;
    case CameraPixelFormat::kRgb24:
      return V4L2_PIX_FMT_RGB24;
    case CameraPixelFormat::kGrey:
      return V4L2_PIX_FMT_GREY;
  }
  return V4L2_PIX_FMT_YUYV;
}

std::string fourcc_text(std::uint32_t f) {
  std::string s(4, ' ');
  for (int i = 0; i < 4; ++i)
    s[static_cast<std::size_t>(i)] = static_cast<char>((f >> (8 * i)) & 0xFF);
  return s;
}

int xioctl(int fd, unsigned long request, void* arg) {
  int rc;
  do {
    rc = v4l2_ioctl(fd, request, arg);
  } while (rc == -1 && errno == EINTR);
  return rc;
}

}  // namespace

struct V4l2Camera::Impl {
  struct Buffer {
    void* start = MAP_FAILED;
    std::size_t length = 0;
  };

  V4l2CameraConfig config;
  Clock& clock;
  int fd = -1;
  std::vector<Buffer> buffers;
  bool streaming = false;
  bool wanted = false;  // start() succeeded once and stop() not called: recover on errors
  int held_buffer = -1;
  int width = 0;
  int height = 0;
  std::size_t stride = 0;
  std::optional<MjpegDecoder> mjpeg;  // made once the size is negotiated
  std::string error;
  CameraCounters counters;
  bool have_sequence = false;
  bool driver_sequence = true;  // the driver's buffer sequence numbers are usable
  std::uint32_t last_driver_sequence = 0;
  std::uint64_t last_sequence = 0;
  // After a reopen the driver numbers frames from 0 again; this offset keeps Frame::sequence
  // increasing across the gap so consumers never see it go backwards.
  bool restarted = false;
  std::int64_t sequence_offset = 0;
  milliseconds backoff{0};
  nanoseconds next_reopen{0};

  Impl(const V4l2CameraConfig& c, Clock& k) : config(c), clock(k) {}

  std::string where() const { return "camera " + config.device + ": "; }

  bool fail(const std::string& what) {
    error = where() + what;
    return false;
  }
  bool fail_errno(const std::string& what) { return fail(what + ": " + std::strerror(errno)); }

  void close_device() noexcept {
    if (fd < 0) return;
    if (streaming) {
      v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      xioctl(fd, VIDIOC_STREAMOFF, &type);
      streaming = false;
    }
    for (auto& b : buffers)
      if (b.start != MAP_FAILED) v4l2_munmap(b.start, b.length);
    buffers.clear();
    held_buffer = -1;
    v4l2_close(fd);
    fd = -1;
  }

  bool set_control(std::uint32_t id, int value, const char* name) {
    v4l2_control ctrl{};
    ctrl.id = id;
    ctrl.value = value;
    if (xioctl(fd, VIDIOC_S_CTRL, &ctrl) != 0)
      return fail_errno(std::string("setting control ") + name + " = " + std::to_string(value));
    return true;
  }

  bool open_and_stream() {
    fd = v4l2_open(config.device.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC, 0);
    if (fd < 0) return fail_errno("cannot open");
    v4l2_capability cap{};
    if (xioctl(fd, VIDIOC_QUERYCAP, &cap) != 0) return fail_errno("not a V4L2 device (QUERYCAP)");
    const std::uint32_t caps =
        (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) return fail("is not a video capture device");
    if (!(caps & V4L2_CAP_STREAMING)) return fail("does not support streaming I/O");

    v4l2_format fmt{};
    fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    fmt.fmt.pix.width = static_cast<std::uint32_t>(config.width);
    fmt.fmt.pix.height = static_cast<std::uint32_t>(config.height);
    fmt.fmt.pix.pixelformat = fourcc_of(config.pixel_format);
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
    if (xioctl(fd, VIDIOC_S_FMT, &fmt) != 0) return fail_errno("setting the format (S_FMT)");
    if (fmt.fmt.pix.pixelformat != fourcc_of(config.pixel_format))
      return fail("pixel format " + fourcc_text(fourcc_of(config.pixel_format)) +
                  " is unsupported (the device offers " + fourcc_text(fmt.fmt.pix.pixelformat) +
                  "; list formats with v4l2-ctl --list-formats-ext)");
    width = static_cast<int>(fmt.fmt.pix.width);
    height = static_cast<int>(fmt.fmt.pix.height);
    // The vision geometry (ground footprint per pixel) assumes the configured size: a rounded
    // size is a configuration error, not something to adapt to silently.
    if (width != config.width || height != config.height)
      return fail("cannot deliver " + std::to_string(config.width) + "x" +
                  std::to_string(config.height) + " " +
                  fourcc_text(fourcc_of(config.pixel_format)) +
                  " (nearest offered: " + std::to_string(width) + "x" + std::to_string(height) +
                  "; list sizes with v4l2-ctl --list-formats-ext)");
    stride = fmt.fmt.pix.bytesperline;
    if (config.pixel_format == CameraPixelFormat::kMjpeg &&
        (!mjpeg || mjpeg->width() != width || mjpeg->height() != height))
      try {
        mjpeg.emplace(width, height);
      } catch (const std::exception& e) {
        return fail(e.what());
      }
    if (stride == 0) {
      const std::size_t bpp = config.pixel_format == CameraPixelFormat::kRgb24  ? 3
                              : config.pixel_format == CameraPixelFormat::kGrey ? 1
                                                                                : 2;
      stride = static_cast<std::size_t>(width) * bpp;
    }

    v4l2_streamparm parm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    parm.parm.capture.timeperframe.numerator = 1;
    parm.parm.capture.timeperframe.denominator = static_cast<std::uint32_t>(config.fps);
    if (xioctl(fd, VIDIOC_S_PARM, &parm) == 0) {
      const auto& tpf = parm.parm.capture.timeperframe;
      if (tpf.numerator != 0 && tpf.denominator != 0) {
        const double actual = static_cast<double>(tpf.denominator) / tpf.numerator;
        if (std::abs(actual - config.fps) > 0.01 * config.fps)
          return fail("cannot run at " + std::to_string(config.fps) + " fps at this size (the " +
                      "driver chose " + std::to_string(actual) + " fps)");
      }
    } else if (errno != ENOTTY && errno != EINVAL) {
      return fail_errno("setting " + std::to_string(config.fps) + " fps (S_PARM)");
    }

    if (config.exposure_absolute) {
      if (!set_control(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL, "exposure_auto")) return false;
      if (!set_control(V4L2_CID_EXPOSURE_ABSOLUTE, *config.exposure_absolute, "exposure_absolute"))
        return false;
    }
    if (config.auto_white_balance &&
        !set_control(V4L2_CID_AUTO_WHITE_BALANCE, *config.auto_white_balance ? 1 : 0,
                     "white_balance_automatic"))
      return false;
    if (config.white_balance_temperature &&
        !set_control(V4L2_CID_WHITE_BALANCE_TEMPERATURE, *config.white_balance_temperature,
                     "white_balance_temperature"))
      return false;

    v4l2_requestbuffers req{};
    req.count = static_cast<std::uint32_t>(config.buffer_count);
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd, VIDIOC_REQBUFS, &req) != 0) return fail_errno("requesting mmap buffers");
    if (req.count < 2) return fail("the driver granted fewer than 2 buffers");
    buffers.resize(req.count);
    for (std::uint32_t i = 0; i < req.count; ++i) {
      v4l2_buffer buf{};
      buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      buf.memory = V4L2_MEMORY_MMAP;
      buf.index = i;
      if (xioctl(fd, VIDIOC_QUERYBUF, &buf) != 0) return fail_errno("QUERYBUF");
      buffers[i].length = buf.length;
      buffers[i].start =
          v4l2_mmap(nullptr, buf.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, buf.m.offset);
      if (buffers[i].start == MAP_FAILED) return fail_errno("mmap of buffer " + std::to_string(i));
      if (xioctl(fd, VIDIOC_QBUF, &buf) != 0) return fail_errno("QBUF");
    }
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd, VIDIOC_STREAMON, &type) != 0) return fail_errno("STREAMON");
    streaming = true;
    restarted = have_sequence || restarted;
    have_sequence = false;
    driver_sequence = true;
    return true;
  }

  void lose_device(const std::string& what) {
    error = where() + what;
    ++counters.errors;
    close_device();
    backoff = config.reopen_backoff_min;
    next_reopen = clock.now() + backoff;
  }

  // Tries to reopen when the back-off allows, waiting at most until `deadline`.
  bool recover(nanoseconds deadline) {
    const nanoseconds wake = std::min(next_reopen, deadline);
    clock.sleep_until(wake);
    if (clock.now() < next_reopen) return false;
    if (open_and_stream()) {
      ++counters.reopens;
      return true;
    }
    close_device();
    backoff = std::min(backoff * 2, config.reopen_backoff_max);
    next_reopen = clock.now() + backoff;
    return false;
  }

  void requeue_held() {
    if (held_buffer < 0 || fd < 0) return;
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = static_cast<std::uint32_t>(held_buffer);
    held_buffer = -1;
    if (xioctl(fd, VIDIOC_QBUF, &buf) != 0)
      lose_device(std::string("QBUF: ") + std::strerror(errno));
  }
};

V4l2Camera::V4l2Camera(const V4l2CameraConfig& config, Clock& clock)
    : impl_(std::make_unique<Impl>(config, clock)) {}

V4l2Camera::~V4l2Camera() {
  stop();
}

bool V4l2Camera::start() {
  Impl& m = *impl_;
  m.close_device();
  if (m.config.width <= 0 || m.config.height <= 0 || m.config.fps <= 0 || m.config.buffer_count < 2)
    return m.fail("width, height and fps must be > 0 and buffer_count >= 2");
  if (!m.open_and_stream()) {
    m.close_device();
    return false;
  }
  m.wanted = true;
  m.error.clear();
  return true;
}

FrameStatus V4l2Camera::next_frame(Frame& frame, milliseconds timeout) {
  Impl& m = *impl_;
  if (!m.wanted) {
    m.error = m.where() + "next_frame() before start()";
    return FrameStatus::kError;
  }
  const nanoseconds deadline = m.clock.now() + timeout;
  m.requeue_held();
  if (m.fd < 0 && !m.recover(deadline)) return FrameStatus::kError;

  pollfd pfd{m.fd, POLLIN, 0};
  const int ready =
      poll(&pfd, 1,
           static_cast<int>(std::max<std::int64_t>(
               0, std::chrono::duration_cast<milliseconds>(deadline - m.clock.now()).count())));
  if (ready == 0) {
    ++m.counters.timeouts;
    return FrameStatus::kTimeout;
  }
  if (ready < 0 && errno == EINTR) return FrameStatus::kTimeout;
  if (ready < 0 || (pfd.revents & (POLLERR | POLLHUP | POLLNVAL))) {
    m.lose_device("the device stopped delivering (poll error; unplugged?)");
    return FrameStatus::kError;
  }
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  if (xioctl(m.fd, VIDIOC_DQBUF, &buf) != 0) {
    if (errno == EAGAIN) {
      ++m.counters.timeouts;
      return FrameStatus::kTimeout;
    }
    m.lose_device(std::string("DQBUF: ") + std::strerror(errno));
    return FrameStatus::kError;
  }
  m.held_buffer = static_cast<int>(buf.index);
  if (buf.flags & V4L2_BUF_FLAG_ERROR) {
    ++m.counters.errors;
    m.error = m.where() + "the driver flagged a corrupted frame";
    return FrameStatus::kError;
  }
  if ((buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC &&
      (buf.timestamp.tv_sec != 0 || buf.timestamp.tv_usec != 0)) {
    frame.timestamp = std::chrono::seconds{buf.timestamp.tv_sec} +
                      std::chrono::microseconds{buf.timestamp.tv_usec};
  } else {
    frame.timestamp = m.clock.now();
  }
  // libv4l2's format emulation (e.g. GREY converted from a YUYV-only device) hands out
  // sequence 0 for every frame: once the driver's numbers stop increasing, count ourselves.
  if (m.have_sequence && m.driver_sequence && buf.sequence <= m.last_driver_sequence)
    m.driver_sequence = false;
  if (!m.have_sequence && m.restarted)
    m.sequence_offset = static_cast<std::int64_t>(m.last_sequence + 1) - buf.sequence;
  if (m.driver_sequence) {
    if (m.have_sequence && buf.sequence > m.last_driver_sequence + 1)
      m.counters.dropped += buf.sequence - m.last_driver_sequence - 1;
    m.last_driver_sequence = buf.sequence;
    frame.sequence = static_cast<std::uint64_t>(m.sequence_offset + buf.sequence);
  } else {
    frame.sequence = m.last_sequence + 1;
  }
  m.have_sequence = true;
  m.last_sequence = frame.sequence;

  const auto* data = static_cast<const std::uint8_t*>(m.buffers[buf.index].start);
  switch (m.config.pixel_format) {
    case CameraPixelFormat::kMjpeg: {
      // A damaged frame (libjpeg warned, e.g. padding before the end marker that some webcams
      // send on every frame) is still delivered, as OpenCV's decoder did.
      if (m.mjpeg->decode(data, buf.bytesused) == MjpegDecoder::Result::kRefused) {
        ++m.counters.errors;
        m.error = m.where() + "MJPEG frame " + std::to_string(buf.sequence) +
                  " did not decode: " + m.mjpeg->error();
        if (m.mjpeg->claimed_width() > 0)
          m.error.append(" (header says ")
              .append(std::to_string(m.mjpeg->claimed_width()))
              .append("x")
              .append(std::to_string(m.mjpeg->claimed_height()))
              .append(")");
        return FrameStatus::kError;
      }
      frame.view = {m.mjpeg->bgr(), m.mjpeg->width(), m.mjpeg->height(), m.mjpeg->stride(),
                    vision::PixelFormat::kBgr24};
      break;
    }
    case CameraPixelFormat::kYuyv:
      frame.view = {data, m.width, m.height, m.stride, vision::PixelFormat::kYuyv};
      break;
    case CameraPixelFormat::kRgb24:
      frame.view = {data, m.width, m.height, m.stride, vision::PixelFormat::kRgb24};
      break;
    case CameraPixelFormat::kGrey:
      frame.view = {data, m.width, m.height, m.stride, vision::PixelFormat::kGrey};
      break;
  }
  ++m.counters.frames;
  return FrameStatus::kOk;
}

void V4l2Camera::stop() noexcept {
  impl_->wanted = false;
  impl_->close_device();
}

std::string V4l2Camera::last_error() const {
  return impl_->error;
}

CameraCounters V4l2Camera::counters() const noexcept {
  return impl_->counters;
}

int V4l2Camera::width() const noexcept {
  return impl_->width;
}

int V4l2Camera::height() const noexcept {
  return impl_->height;
}

}  // namespace weedspray::io::hw
