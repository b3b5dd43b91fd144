// SPDX-License-Identifier: Apache-2.0
#include "lab/experiments/speed_target.hpp"

#include <algorithm>

namespace weedspray::lab::experiments {

AskedFlow asked_flow(const control::SprayLawConfig& law, double density, double speed_m_per_s,
                     double limit_l_per_min) noexcept {
  const double target = control::target_flow_l_per_min(law, density, speed_m_per_s);
  const double asked = std::min(target, std::max(limit_l_per_min, 0.0));
  return {asked, target - asked};
}

AskedFlow speed_following_flow(double share, double reference_flow_l_per_min,
                               double reference_speed_m_per_s, double speed_m_per_s,
                               double limit_l_per_min) noexcept {
  control::SprayLawConfig law;
  law.nominal_flow_l_per_min = reference_flow_l_per_min;
  law.nominal_speed_m_per_s = reference_speed_m_per_s;
  law.max_density = 1.0;
  return asked_flow(law, share, speed_m_per_s, limit_l_per_min);
}

}  // namespace weedspray::lab::experiments
