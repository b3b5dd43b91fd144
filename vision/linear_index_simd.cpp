// SPDX-License-Identifier: Apache-2.0
// Hand-written with OpenCV's universal intrinsics (one source for SSE2/AVX2 and NEON):
// cv::cvtColor + cv::calcHist would need temporary images and three passes over the frame;
// this needs one and allocates nothing. All arithmetic is in 16-bit lanes: modulo 2^16 for
// the RGB formulas (they end in [0, 32767]), saturating for the YUYV one (its max(0, ...)),
// so the results equal vegetation_index_of / cive_of_yuv bit for bit.
#include "vision/linear_index_simd.hpp"

#include <opencv2/core/hal/intrin.hpp>

namespace weedspray::vision {
namespace {

// Eight partial histograms break the store-to-load dependency between equal values: CIVE
// packs bare soil into a handful of levels, so with one histogram nearly every increment
// would wait for the previous one to the same bin.
constexpr int kPartialHistograms = 8;

struct SplitHistogram {
  std::uint32_t bins[kPartialHistograms][256] = {};
  // Bytes taken from two 64-bit halves of the register: GCC otherwise spills the vector once
  // per byte.
  void add16(const cv::v_uint8x16& values) {
    const cv::v_uint64x2 halves = cv::v_reinterpret_as_u64(values);
    add8(halves.get0(), &bins[0]);
    add8(cv::v_extract_n<1>(halves), &bins[4]);
  }
  static void add8(std::uint64_t values, std::uint32_t (*partial)[256]) {
    // Bytes 0-3 and 4-7 go to the same four histograms (eight in all with the other half).
    for (int i = 0; i < 8; ++i) ++partial[i % 4][(values >> (8 * i)) & 0xFF];
  }
  void merge_into(Histogram& histogram) const {
    for (int level = 0; level < 256; ++level) {
      for (int i = 0; i < kPartialHistograms; ++i) histogram[level] += bins[i][level];
    }
  }
};

// GCC turns a multiply by a constant vector into longer shift-and-add chains; read through
// a volatile once per call, the weights are opaque and stay one multiply instruction each.
volatile std::uint16_t g_cive_weights[3] = {52, 28, 25};  // green, red, blue
volatile std::uint16_t g_yuv_cive_weights[2] = {71, 87};  // U, V

struct CiveFormula {
  cv::v_uint16x8 green_weight = cv::v_setall_u16(g_cive_weights[0]);
  cv::v_uint16x8 red_weight = cv::v_setall_u16(g_cive_weights[1]);
  cv::v_uint16x8 blue_weight = cv::v_setall_u16(g_cive_weights[2]);
  cv::v_uint16x8 offset = cv::v_setall_u16(kCiveOffset);

  static std::uint8_t scalar(int r, int g, int b) {
    return static_cast<std::uint8_t>((kCiveOffset + 52 * g - 28 * r - 25 * b) >> 7);
  }
  // The _wrap forms: OpenCV's 16-bit operators saturate, and its operator* does so through a
  // widening multiply and a pack, several times slower.
  cv::v_uint16x8 vector(const cv::v_uint16x8& r, const cv::v_uint16x8& g,
                        const cv::v_uint16x8& b) const {
    const cv::v_uint16x8 plus = cv::v_add_wrap(offset, cv::v_mul_wrap(g, green_weight));
    const cv::v_uint16x8 minus =
        cv::v_add_wrap(cv::v_mul_wrap(r, red_weight), cv::v_mul_wrap(b, blue_weight));
    return cv::v_sub_wrap(plus, minus) >> 7;
  }
};

struct ExgRawFormula {
  cv::v_uint16x8 offset = cv::v_setall_u16(512);

  static std::uint8_t scalar(int r, int g, int b) {
    return static_cast<std::uint8_t>((2 * g - r - b + 512) >> 2);
  }
  cv::v_uint16x8 vector(const cv::v_uint16x8& r, const cv::v_uint16x8& g,
                        const cv::v_uint16x8& b) const {
    return cv::v_sub_wrap(cv::v_add_wrap(offset, g << 1), cv::v_add_wrap(r, b)) >> 2;
  }
};

template <typename Formula>
void linear_rows(const ImageView& frame, PixelRect rect, std::uint8_t* out, std::size_t out_stride,
                 Histogram& histogram) {
  const bool bgr = frame.format == PixelFormat::kBgr24;
  const Formula formula;
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
      // The formulas end in [0, 255]: a plain signed pack (one instruction) needs no clamp.
      const cv::v_uint8x16 value =
          cv::v_pack_u(cv::v_reinterpret_as_s16(formula.vector(red_low, green_low, blue_low)),
                       cv::v_reinterpret_as_s16(formula.vector(red_high, green_high, blue_high)));
      cv::v_store(row_out + x, value);
      split.add16(value);
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

void cive_yuyv_rows_simd(const ImageView& frame, PixelRect rect, std::uint8_t* out,
                         std::size_t out_stride, Histogram& histogram) {
  const cv::v_uint16x8 offset = cv::v_setall_u16(36670);
  const cv::v_uint16x8 u_weight = cv::v_setall_u16(g_yuv_cive_weights[0]);
  const cv::v_uint16x8 v_weight = cv::v_setall_u16(g_yuv_cive_weights[1]);
  const cv::v_uint16x8 low_byte = cv::v_setall_u16(0xFF);
  SplitHistogram split;
  for (int y = 0; y < rect.height; ++y) {
    const std::uint8_t* in = frame.data + (rect.y + y) * frame.stride + rect.x * 2;
    std::uint8_t* row_out = out + y * out_stride;
    int x = 0;
    for (; x + 16 <= rect.width; x += 16) {
      // 16 pixels: luma Y0..Y15 and chroma U0 V0 U1 V1 ... (one U, V per pixel pair).
      cv::v_uint8x16 luma, chroma;
      cv::v_load_deinterleave(in + 2 * x, luma, chroma);
      const cv::v_uint16x8 pairs = cv::v_reinterpret_as_u16(chroma);
      const cv::v_uint16x8 u = pairs & low_byte;
      const cv::v_uint16x8 v = pairs >> 8;
      // 71 U + 87 V <= 40290: fits 16 bits.
      const cv::v_uint16x8 chroma_term =
          cv::v_add_wrap(cv::v_mul_wrap(u, u_weight), cv::v_mul_wrap(v, v_weight));
      cv::v_uint16x8 chroma_low, chroma_high;
      cv::v_zip(chroma_term, chroma_term, chroma_low, chroma_high);  // both pixels of a pair
      cv::v_uint16x8 luma_low, luma_high;
      cv::v_expand(luma, luma_low, luma_high);
      // OpenCV's 16-bit - saturates at 0: exactly cive_of_yuv's max(0, ...).
      const cv::v_uint16x8 value_low = (offset - luma_low - chroma_low) >> 7;
      const cv::v_uint16x8 value_high = (offset - luma_high - chroma_high) >> 7;
      const cv::v_uint8x16 value = cv::v_pack(value_low, value_high);  // saturates at 255
      cv::v_store(row_out + x, value);
      split.add16(value);
    }
    for (; x + 1 < rect.width; x += 2) {
      const std::uint8_t* pair = in + 2 * x;
      row_out[x] = cive_of_yuv(pair[0], pair[1], pair[3]);
      row_out[x + 1] = cive_of_yuv(pair[2], pair[1], pair[3]);
      ++split.bins[0][row_out[x]];
      ++split.bins[1][row_out[x + 1]];
    }
  }
  split.merge_into(histogram);
}

void cive_rows_simd(const ImageView& frame, PixelRect rect, std::uint8_t* out,
                    std::size_t out_stride, Histogram& histogram) {
  linear_rows<CiveFormula>(frame, rect, out, out_stride, histogram);
}

void exg_raw_rows_simd(const ImageView& frame, PixelRect rect, std::uint8_t* out,
                       std::size_t out_stride, Histogram& histogram) {
  linear_rows<ExgRawFormula>(frame, rect, out, out_stride, histogram);
}

}  // namespace weedspray::vision
