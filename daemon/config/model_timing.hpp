// SPDX-License-Identifier: Apache-2.0
// How long each camera's weed source takes per frame on this machine, for --check-config: a
// camera and model that need a large network input cost a frame's time many times over, and
// frames that arrive meanwhile are skipped (ground never looked at), so the user sees the cost
// before the field rather than in frames_skipped.
#pragma once

#include <string>
#include <vector>

#include "daemon/config/config.hpp"

namespace weedspray::daemon {

// One line per camera, "camera[0]: dnn on 1280x800 frames, network input 1376x864: 262 ms per
// frame on this machine (one thread)", each the median of `frames` frames after one warm-up;
// empty when the weed source needs no model. The network also runs once at each camera's own
// input size here (the load-time check runs it at the spec's): a model that fails there is
// refused as a VisionKeyError naming vision.model.
[[nodiscard]] std::vector<std::string> time_model_use(const Config& config, int frames = 3);

}  // namespace weedspray::daemon
