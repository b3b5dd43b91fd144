// SPDX-License-Identifier: Apache-2.0
// How sprayctl shows weedsprayd's values: each property's unit, its text for people (three
// decimals, structures as sentences) and the timestamp every line of output carries.
#pragma once

#include <chrono>
#include <string>

#include "daemon/sprayctl/bus_values.hpp"

namespace weedspray::sprayctl {

// The unit of property `name` ("MPa", "L/min", ...); "" for a property without one.
const char* unit_of(const std::string& name);

// Every property with a unit, as a JSON object name -> unit.
Value units_object();

// Property `name`'s value as `sprayctl status` shows it.
std::string text_value(const std::string& name, const Value& value);

// `time` as RFC 3339 UTC with milliseconds (2026-11-28T15:40:12.123Z) and as the local time
// of day with milliseconds (15:40:12.123).
std::string utc_timestamp(std::chrono::system_clock::time_point time);
std::string local_time_of_day(std::chrono::system_clock::time_point time);

}  // namespace weedspray::sprayctl
