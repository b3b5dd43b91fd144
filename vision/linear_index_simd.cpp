// Hand-written with OpenCV's universal intrinsics (one source for SSE2/AVX2 and NEON):
// cv::cvtColor + cv::calcHist would need temporary images and three passes over the frame;
// this needs one and allocates nothing. All arithmetic is modulo 2^16 in 16-bit lanes; the
// fixed-point formulas of vegetation_index.hpp end in [0, 32767], so the result equals
// vegetation_index_of bit for bit.
#include "vision/linear_index_simd.hpp"

#include <opencv2/core/hal/intrin.hpp>

namespace weedspray::vision {
namespace {

// Four partial histograms break the store-to-load dependency between equal neighbouring
// values (plant and soil pixels come in runs), which otherwise serialises the increments.
struct SplitHistogram {
  std::uint32_t bins[4][256] = {};
  void add16(const std::uint8_t* values) {
    for (int i = 0; i < 16; i += 4) {
      ++bins[0][values[i]];
      ++bins[1][values[i + 1]];
      ++bins[2][values[i + 2]];
      ++bins[3][values[i + 3]];
    }
  }
  void merge_into(Histogram& histogram) const {
    for (int level = 0; level < 256; ++level) {
      histogram[level] += bins[0][level] + bins[1][level] + bins[2][level] + bins[3][level];
    }
  }
};

struct CiveFormula {
  static std::uint8_t scalar(int r, int g, int b) {
    return static_cast<std::uint8_t>((kCiveOffset + 52 * g - 28 * r - 25 * b) >> 7);
  }
  static cv::v_uint16x8 vector(const cv::v_uint16x8& r, const cv::v_uint16x8& g,
                               const cv::v_uint16x8& b) {
    // The _wrap forms: OpenCV's 16-bit operators saturate, and its operator* does so through
    // a widening multiply and a pack, several times slower.
    const cv::v_uint16x8 plus =
        cv::v_add_wrap(cv::v_setall_u16(kCiveOffset), cv::v_mul_wrap(g, cv::v_setall_u16(52)));
    const cv::v_uint16x8 minus = cv::v_add_wrap(cv::v_mul_wrap(r, cv::v_setall_u16(28)),
                                                cv::v_mul_wrap(b, cv::v_setall_u16(25)));
    return cv::v_sub_wrap(plus, minus) >> 7;
  }
};

struct ExgRawFormula {
  static std::uint8_t scalar(int r, int g, int b) {
    return static_cast<std::uint8_t>((2 * g - r - b + 512) >> 2);
  }
  static cv::v_uint16x8 vector(const cv::v_uint16x8& r, const cv::v_uint16x8& g,
                               const cv::v_uint16x8& b) {
    return cv::v_sub_wrap(cv::v_add_wrap(cv::v_setall_u16(512), g << 1), cv::v_add_wrap(r, b)) >> 2;
  }
};

template <typename Formula>
void linear_rows(const ImageView& frame, PixelRect rect, std::uint8_t* out, std::size_t out_stride,
                 Histogram& histogram) {
  const bool bgr = frame.format == PixelFormat::kBgr24;
  SplitHistogram split;
  for (int y = 0; y < rect.height; ++y) {
    const std::uint8_t* in = frame.data + (rect.y + y) * frame.stride + rect.x * 3;
    std::uint8_t* row_out = out + y * out_stride;
    int x = 0;
    for (; x + 16 <= rect.width; x += 16) {
      cv::v_uint8x16 first, green, third;
      cv::v_load_deinterleave(in + 3 * x, first, green, third);
      const cv::v_uint8x16& red = bgr ? third : first;
      const cv::v_uint8x16& blue = bgr ? first : third;
      cv::v_uint16x8 red_low, red_high, green_low, green_high, blue_low, blue_high;
      cv::v_expand(red, red_low, red_high);
      cv::v_expand(green, green_low, green_high);
      cv::v_expand(blue, blue_low, blue_high);
      const cv::v_uint8x16 value = cv::v_pack(Formula::vector(red_low, green_low, blue_low),
                                              Formula::vector(red_high, green_high, blue_high));
      cv::v_store(row_out + x, value);
      split.add16(row_out + x);
    }
    for (; x < rect.width; ++x) {
      const std::uint8_t* pixel = in + 3 * x;
      const int r = bgr ? pixel[2] : pixel[0];
      const int b = bgr ? pixel[0] : pixel[2];
      row_out[x] = Formula::scalar(r, pixel[1], b);
      ++split.bins[0][row_out[x]];
    }
  }
  split.merge_into(histogram);
}

}  // namespace

void cive_rows_simd(const ImageView& frame, PixelRect rect, std::uint8_t* out,
                    std::size_t out_stride, Histogram& histogram) {
  linear_rows<CiveFormula>(frame, rect, out, out_stride, histogram);
}

void exg_raw_rows_simd(const ImageView& frame, PixelRect rect, std::uint8_t* out,
                       std::size_t out_stride, Histogram& histogram) {
  linear_rows<ExgRawFormula>(frame, rect, out, out_stride, histogram);
}

}  // namespace weedspray::vision
