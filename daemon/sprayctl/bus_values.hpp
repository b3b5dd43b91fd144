// SPDX-License-Identifier: Apache-2.0
// sprayctl's reading of weedsprayd's D-Bus values: each property as typed JSON (numbers,
// booleans, strings; a structure as an object with named fields), the exit statuses, and the
// error a failed call becomes.
#pragma once

#include <systemd/sd-bus.h>

#include <map>
#include <nlohmann/json.hpp>
#include <string>

namespace weedspray::sprayctl {

using Value = nlohmann::json;
using Properties = std::map<std::string, Value>;

// Exit statuses, as sprayctl(1) documents them.
inline constexpr int kExitRefused = 1;      // the daemon refused the request, or it failed
inline constexpr int kExitUsage = 2;        // no command, an unknown one, a bad argument
inline constexpr int kExitUnreachable = 3;  // weedsprayd not on the bus, no bus, or no answer

struct BusError {
  std::string message;
  int exit_status = kExitRefused;
};

// Throws BusError naming `what` when an sd-bus call returned an error.
void check(int r, const char* what);

// Reads one variant (of the signatures the service uses) from `m`.
Value read_variant(sd_bus_message* m);

// Reads an a{sv} dictionary.
Properties read_properties(sd_bus_message* m);

}  // namespace weedspray::sprayctl
