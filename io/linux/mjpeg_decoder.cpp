// SPDX-License-Identifier: Apache-2.0
#include "io/linux/mjpeg_decoder.hpp"

#include <turbojpeg.h>

#include <climits>
#include <stdexcept>
#include <string>

namespace weedspray::io::hw {

MjpegDecoder::MjpegDecoder(int width, int height) : width_(width), height_(height) {
  if (width <= 0 || height <= 0 || width > INT_MAX / 3 / height)
    throw std::invalid_argument("MJPEG decoder: bad frame size " + std::to_string(width) + "x" +
                                std::to_string(height));
  bgr_.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3);
  handle_ = tjInitDecompress();
  if (handle_ == nullptr)
    throw std::runtime_error(std::string("MJPEG decoder: libjpeg-turbo: ") +
                             tjGetErrorStr2(nullptr));
}

MjpegDecoder::~MjpegDecoder() {
  if (handle_ != nullptr) tjDestroy(handle_);
}

MjpegDecoder::Result MjpegDecoder::decode(const std::uint8_t* jpeg, std::size_t size) noexcept {
  error_ = "";
  claimed_width_ = claimed_height_ = 0;
  if (jpeg == nullptr || size == 0 || size > ULONG_MAX) {
    error_ = "empty frame";
    return Result::kRefused;
  }
  int subsampling = 0;
  int colorspace = 0;
  // A warning (e.g. stray bytes between markers) still yields the header's size.
  bool warned = false;
  if (tjDecompressHeader3(handle_, jpeg, static_cast<unsigned long>(size), &claimed_width_,
                          &claimed_height_, &subsampling, &colorspace) != 0) {
    error_ = tjGetErrorStr2(handle_);
    if (tjGetErrorCode(handle_) != TJERR_WARNING) {
      claimed_width_ = claimed_height_ = 0;
      return Result::kRefused;
    }
    warned = true;
  }
  if (claimed_width_ != width_ || claimed_height_ != height_) {
    error_ = "the JPEG header's size is not the negotiated frame size";
    return Result::kRefused;
  }
  // Default flags: libjpeg-turbo completes a frame after a warning (corrupt data), as
  // OpenCV's decoder did; the caller learns of it through kDamaged.
  if (tjDecompress2(handle_, jpeg, static_cast<unsigned long>(size), bgr_.data(), width_,
                    static_cast<int>(stride()), height_, TJPF_BGR, 0) != 0) {
    error_ = tjGetErrorStr2(handle_);
    return tjGetErrorCode(handle_) == TJERR_WARNING ? Result::kDamaged : Result::kRefused;
  }
  return warned ? Result::kDamaged : Result::kOk;
}

}  // namespace weedspray::io::hw
