// SPDX-License-Identifier: Apache-2.0
#include "fleet/motion.hpp"

#include <cmath>

namespace weedspray::fleet {

nlohmann::json motion_payload(const MotionSample& sample) {
  return {{"m_per_s", sample.speed_m_per_s},
          {"distance_m", sample.distance_m},
          {"t_ns", sample.time_ns}};
}

std::optional<MotionSample> parse_motion(std::string_view payload) {
  constexpr std::size_t kMaxBytes = 256;  // three numbers
  if (payload.size() > kMaxBytes) return std::nullopt;
  const auto json = nlohmann::json::parse(payload, nullptr, false);
  if (json.is_discarded() || !json.is_object()) return std::nullopt;
  const auto speed = json.find("m_per_s");
  const auto distance = json.find("distance_m");
  const auto time = json.find("t_ns");
  if (speed == json.end() || distance == json.end() || time == json.end() || !speed->is_number() ||
      !distance->is_number() || !time->is_number_unsigned()) {
    return std::nullopt;
  }
  MotionSample sample{speed->get<double>(), distance->get<double>(), time->get<std::uint64_t>()};
  if (!std::isfinite(sample.speed_m_per_s) || sample.speed_m_per_s < 0 ||
      !std::isfinite(sample.distance_m)) {
    return std::nullopt;
  }
  return sample;
}

}  // namespace weedspray::fleet
