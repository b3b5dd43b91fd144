// SPDX-License-Identifier: Apache-2.0
// The target flow a rate controller asks of a nozzle as the ground speed moves, for the volume
// experiments: a demand drawn at a reference speed (a share of the nozzle's reference flow, or a
// weed density under a rate law) becomes each step's target through the daemon's own rate law,
// control::target_flow_l_per_min (q = 60 D w v u / k): at 20 % more speed every nozzle's target is
// 20 % higher, the volume per area kept.
//
// A target above what the line can deliver (the nozzle's full-open flow in the experiment's
// reference) is clipped to it, and the volume is judged against the clipped target: it is what the
// controller is asked, and no controller sprays more than a held-open valve passes. The clipped
// volume is reported beside the error so that a demand the machine cannot meet shows, rather than
// counting as the controller's error. Clipping, not a demand drawn with headroom for the top speed,
// keeps each experiment's levels what they are at the reference speed (the L16's 100 % stays held
// open there); the field experiments draw their shares with headroom as well, so they clip nothing.
#pragma once

#include "control/spray_rate_law.hpp"

namespace weedspray::lab::experiments {

struct AskedFlow {
  double flow_l_per_min = 0.0;     // the target asked: the law's flow, at most the limit
  double clipped_l_per_min = 0.0;  // the law's flow above the limit (not asked)
};

// The law's target at a ground speed, clipped at limit_l_per_min (what the line can deliver).
AskedFlow asked_flow(const control::SprayLawConfig& law, double density, double speed_m_per_s,
                     double limit_l_per_min) noexcept;

// A nozzle whose demand at reference_speed_m_per_s is `share` of reference_flow_l_per_min: the
// rate law with that flow as its nominal flow at the reference speed and the share as its density
// (k = 1), that is share x reference flow x speed / reference speed, clipped at the limit.
AskedFlow speed_following_flow(double share, double reference_flow_l_per_min,
                               double reference_speed_m_per_s, double speed_m_per_s,
                               double limit_l_per_min) noexcept;

// Running volumes of asked flows over a run [L].
struct AskedVolume {
  double asked_l = 0.0;
  double clipped_l = 0.0;

  void add(const AskedFlow& flow, double dt_s) noexcept {
    asked_l += flow.flow_l_per_min * dt_s / 60.0;
    clipped_l += flow.clipped_l_per_min * dt_s / 60.0;
  }
  // The clipped volume as a share of the law's (asked + clipped) [%].
  double clipped_pct() const noexcept {
    const double law_l = asked_l + clipped_l;
    return law_l > 0.0 ? clipped_l / law_l * 100.0 : 0.0;
  }
};

}  // namespace weedspray::lab::experiments
