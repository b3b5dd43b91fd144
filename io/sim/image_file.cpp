// SPDX-License-Identifier: Apache-2.0
#include "io/sim/image_file.hpp"

#include <png.h>
#include <turbojpeg.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <iterator>
#include <memory>
#include <vector>

namespace weedspray::io::sim {
namespace {

std::string lower_extension(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

cv::Mat read_png(const std::filesystem::path& path, std::string& error) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (png_image_begin_read_from_file(&image, path.c_str()) == 0) {
    error = path.string() + ": " + image.message;
    return {};
  }
  image.format = PNG_FORMAT_BGR;
  cv::Mat bgr(static_cast<int>(image.height), static_cast<int>(image.width), CV_8UC3);
  if (png_image_finish_read(&image, nullptr, bgr.data, static_cast<png_int_32>(bgr.step),
                            nullptr) == 0) {
    error = path.string() + ": " + image.message;
    png_image_free(&image);
    return {};
  }
  return bgr;
}

cv::Mat read_jpeg(const std::filesystem::path& path, std::string& error) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<unsigned char> data((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) {
    error = path.string() + ": cannot read the file";
    return {};
  }
  const std::unique_ptr<void, int (*)(tjhandle)> decoder(tjInitDecompress(), tjDestroy);
  int width = 0, height = 0, subsampling = 0, colorspace = 0;
  if (!decoder || tjDecompressHeader3(decoder.get(), data.data(), data.size(), &width, &height,
                                      &subsampling, &colorspace) != 0) {
    error = path.string() + ": not a JPEG image (" + tjGetErrorStr2(decoder.get()) + ")";
    return {};
  }
  cv::Mat bgr(height, width, CV_8UC3);
  if (tjDecompress2(decoder.get(), data.data(), data.size(), bgr.data, width,
                    static_cast<int>(bgr.step), height, TJPF_BGR, TJFLAG_ACCURATEDCT) != 0) {
    error = path.string() + ": " + tjGetErrorStr2(decoder.get());
    return {};
  }
  return bgr;
}

}  // namespace

bool is_readable_image(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

cv::Mat read_bgr_image(const std::filesystem::path& path, std::string& error) {
  const std::string ext = lower_extension(path);
  if (ext == ".png") return read_png(path, error);
  if (ext == ".jpg" || ext == ".jpeg") return read_jpeg(path, error);
  error = path.string() + ": not a PNG or JPEG file";
  return {};
}

}  // namespace weedspray::io::sim
