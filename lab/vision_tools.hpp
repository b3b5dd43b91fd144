// SPDX-License-Identifier: Apache-2.0
// segment and bench-vision subcommands (lab/vision_segment.cpp, lab/vision_bench.cpp).
#pragma once

#include <CLI/CLI.hpp>

namespace weedspray::lab {

void add_segment_command(CLI::App& app);
void add_bench_vision_command(CLI::App& app);

}  // namespace weedspray::lab
