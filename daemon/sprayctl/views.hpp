// SPDX-License-Identifier: Apache-2.0
// What sprayctl prints: the status (text or typed JSON), one monitor event, one frame of the
// live view, and the calibrations it follows to their end.
#pragma once

#include <chrono>
#include <iosfwd>
#include <string>

#include "daemon/sprayctl/bus_client.hpp"

namespace weedspray::sprayctl {

void print_status(std::ostream& out, const Properties& p, bool json,
                  std::chrono::system_clock::time_point now);

void print_event(std::ostream& out, const std::string& kind, const std::string& name,
                 const Value& value, bool json, std::chrono::system_clock::time_point now);

// One screen of `sprayctl top`: state, pressure, flow, speed, L/ha, tank, vision, each
// nozzle's duty as a bar with its health, and each latched alarm with what to do.
std::string top_frame(const Properties& p, std::chrono::system_clock::time_point now);

// `sprayctl top`: a frame every `interval_s` until Ctrl-C or `frames` frames (0: no end),
// redrawn in place on a terminal.
int run_top(BusClient& client, double interval_s, int frames);

int run_wheel_calibration(BusClient& client, double run_distance_m, double timeout_s);
int run_meter_calibration(BusClient& client, double catch_test_s, double volume_l);
int run_nozzle_calibration(BusClient& client, double timeout_s);
// Commissioning: one valve, or the pump alone, followed until done (output_test_commands.cpp).
int run_valve_test(BusClient& client, std::uint32_t nozzle, double duty_pct, double seconds);
int run_pump_test(BusClient& client, double seconds);
// The RawInputs list, one input a line (or one JSON object).
void print_inputs(std::ostream& out, const Value& inputs, bool json,
                  std::chrono::system_clock::time_point now);

}  // namespace weedspray::sprayctl
