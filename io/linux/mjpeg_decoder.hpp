// SPDX-License-Identifier: Apache-2.0
#pragma once
// One MJPEG frame (a whole JPEG image) decoded to BGR24 of the negotiated capture size with
// libjpeg-turbo's TurboJPEG API. The header is read first and a frame of any other size is
// refused before anything is allocated: a USB bit error in a header must not make the capture
// thread allocate what the header claims (cv::imdecode allocates up to a gigapixel, 3 GB,
// before it reads the data). The output buffer is allocated once, here.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace weedspray::io::hw {

class MjpegDecoder {
 public:
  enum class Result {
    kOk,
    kDamaged,  // decoded, but libjpeg warned (e.g. extraneous bytes): the image may be partial
    kRefused,  // not decoded: not a JPEG, wrong size, or a fatal decoder error (see error())
  };

  // Throws std::invalid_argument for a size <= 0, std::runtime_error when libjpeg-turbo
  // cannot make a decompressor.
  MjpegDecoder(int width, int height);
  ~MjpegDecoder();
  MjpegDecoder(const MjpegDecoder&) = delete;
  MjpegDecoder& operator=(const MjpegDecoder&) = delete;

  Result decode(const std::uint8_t* jpeg, std::size_t size) noexcept;

  // The last decode's image: width() x height() BGR24, stride() bytes a row.
  const std::uint8_t* bgr() const noexcept { return bgr_.data(); }
  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }
  std::size_t stride() const noexcept { return static_cast<std::size_t>(width_) * 3; }

  // Why the last decode was refused or damaged; points into static or decoder-owned text,
  // valid until the next decode.
  const char* error() const noexcept { return error_; }
  // The size a refused frame's header claimed (0 x 0 when it had no readable header).
  int claimed_width() const noexcept { return claimed_width_; }
  int claimed_height() const noexcept { return claimed_height_; }

 private:
  void* handle_ = nullptr;  // tjhandle
  int width_;
  int height_;
  std::vector<std::uint8_t> bgr_;
  const char* error_ = "";
  int claimed_width_ = 0;
  int claimed_height_ = 0;
};

}  // namespace weedspray::io::hw
