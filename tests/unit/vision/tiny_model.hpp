// SPDX-License-Identifier: Apache-2.0
// tests/data/tiny-3class.onnx: a hand-set network whose class k is the strongest of input
// channels R, G, B (after the spec's mean, scale and order), at its input's resolution.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace weedspray::vision::test {

inline std::vector<std::uint8_t> tiny_model() {
  const std::string path = std::string(WEEDSPRAY_SOURCE_DIR) + "/tests/data/tiny-3class.onnx";
  std::ifstream file(path, std::ios::binary);
  EXPECT_TRUE(file) << path;
  return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

}  // namespace weedspray::vision::test
