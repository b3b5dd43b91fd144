// SPDX-License-Identifier: Apache-2.0
// gnss.source = "fleet": the owning board's fix, from its motion samples, as this board's own
// GNSS fix. The fix is stamped with the time it was taken on this board's clock (the owning
// board's stamp plus the clocks' offset that SharedMotionTracker estimates for the speed), and
// moves on at the shared speed along its heading: whoever reads it carries it forward to its
// own time as it does a receiver's fix (antenna_at, daemon/records/map_geometry.hpp), and ages
// it against gnss.lost_fix_timeout_s like one. Pure: the control loop calls it for each new
// sample; no allocation, no lock, no clock.
#pragma once

#include "daemon/sprayer/ground_speed.hpp"
#include "daemon/sprayer/shared_motion.hpp"

namespace weedspray::daemon {

// The GNSS sample for the latest shared motion sample that `tracker` took. A sample without a
// fix gives a fix of mode none at its arrival (the owning board has no usable fix: lost at once,
// as when a receiver reports none).
[[nodiscard]] GnssSample shared_gnss_sample(const SharedMotionSample& latest,
                                            const SharedMotionTracker& tracker) noexcept;

}  // namespace weedspray::daemon
