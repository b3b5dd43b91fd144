// SPDX-License-Identifier: Apache-2.0
#include "fleet/motion.hpp"

#include <cmath>

namespace weedspray::fleet {

nlohmann::json motion_payload(const MotionSample& sample) {
  nlohmann::json json = {{"m_per_s", sample.speed_m_per_s},
                         {"distance_m", sample.distance_m},
                         {"t_ns", sample.time_ns}};
  const MotionFix& fix = sample.fix;
  if (fix.present() && std::isfinite(fix.latitude_deg) && std::isfinite(fix.longitude_deg)) {
    json["lat"] = fix.latitude_deg;
    json["lon"] = fix.longitude_deg;
    if (std::isfinite(fix.heading_deg)) json["heading_deg"] = fix.heading_deg;
    json["fix"] = fix.mode;
    json["fix_t_ns"] = fix.time_ns;
    if (fix.utc_ns > 0) json["utc_ns"] = fix.utc_ns;
  }
  return json;
}

namespace {

// The fix fields of a motion payload; mode 0 unless all are there and sound.
MotionFix parse_fix(const nlohmann::json& json) {
  const auto number = [&json](const char* key) -> const nlohmann::json* {
    const auto it = json.find(key);
    return it != json.end() && it->is_number() ? &*it : nullptr;
  };
  const nlohmann::json* mode = number("fix");
  const nlohmann::json* lat = number("lat");
  const nlohmann::json* lon = number("lon");
  const nlohmann::json* time = number("fix_t_ns");
  if (mode == nullptr || lat == nullptr || lon == nullptr || time == nullptr ||
      !mode->is_number_unsigned() || !time->is_number_unsigned()) {
    return {};
  }
  MotionFix fix;
  fix.mode = mode->get<std::uint32_t>();
  fix.latitude_deg = lat->get<double>();
  fix.longitude_deg = lon->get<double>();
  fix.time_ns = time->get<std::uint64_t>();
  if (const nlohmann::json* heading = number("heading_deg"))
    fix.heading_deg = heading->get<double>();
  if (const nlohmann::json* utc = number("utc_ns"); utc != nullptr && utc->is_number_integer())
    fix.utc_ns = utc->get<std::int64_t>();
  const bool sound = fix.present() && std::abs(fix.latitude_deg) <= 90 &&
                     std::abs(fix.longitude_deg) <= 180 &&
                     (std::isnan(fix.heading_deg) || std::isfinite(fix.heading_deg));
  return sound ? fix : MotionFix{};
}

}  // namespace

std::optional<MotionSample> parse_motion(std::string_view payload) {
  constexpr std::size_t kMaxBytes = 512;  // eight numbers
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
  MotionSample sample{
      speed->get<double>(), distance->get<double>(), time->get<std::uint64_t>(), {}};
  if (!std::isfinite(sample.speed_m_per_s) || sample.speed_m_per_s < 0 ||
      !std::isfinite(sample.distance_m)) {
    return std::nullopt;
  }
  sample.fix = parse_fix(json);
  return sample;
}

}  // namespace weedspray::fleet
