// SPDX-License-Identifier: Apache-2.0
// Counting vegetation pixels (index > threshold) in the index image (internal to vision/).
#pragma once

#include <cstddef>
#include <cstdint>

namespace weedspray::vision {

// Number of bytes in row[0, length) greater than threshold.
std::uint32_t count_above(const std::uint8_t* row, int length, std::uint8_t threshold);

// column_counts[x] += (row[x] > threshold) for x in [0, length).
void accumulate_columns_above(const std::uint8_t* row, int length, std::uint8_t threshold,
                              std::uint32_t* column_counts);

}  // namespace weedspray::vision
