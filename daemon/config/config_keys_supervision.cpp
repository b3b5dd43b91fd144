// SPDX-License-Identifier: Apache-2.0
// The configuration keys of [alarms], [log], [sim], [fleet], [cab]: limits, records, simulation and
// the machine's other boards.
#include <climits>

#include "daemon/config/config_key_tables.hpp"

// GCC 12 reports a false -Wmaybe-uninitialized inside std::variant<..., std::string> when the
// key table is built (GCC bug 107138 and relatives); the table is plain constant data.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace weedspray::daemon::key_tables {

void append_supervision_keys(std::vector<KeySpec<Config>>& keys) {
  // clang-format off
  keys.insert(keys.end(), {
    // [alarms]
    {WS_KEY(alarms, over_pressure_mpa), 0.9, 0.1, 10, "MPa",
     "over-pressure: pump off and Fault; must lie below pressure.sensor_max_mpa (a sensor that "
     "saturates at its full scale never reads above it)"},
    {WS_KEY(alarms, sensor_fault_low_ma), 3.6, 3.0, 3.8, "mA",
     "a loop current below this is a broken sensor wire or an unpowered sensor (NAMUR NE 43: "
     "3.6 and below is a failure, 3.8 the bottom of the measuring range); the range keeps a cut "
     "wire (0-1 mA) a fault"},
    {WS_KEY(alarms, sensor_fault_high_ma), 21.0, 20.5, 22, "mA",
     "a loop current above this is a shorted sensor (NAMUR NE 43: 21 and above is a failure, "
     "20.5 the top of the measuring range)"},
    {WS_KEY(alarms, blocked_pressure_mpa), 0.7, 0.05, 10, "MPa",
     "line blocked: pressure above this while spraying ..."},
    {WS_KEY(alarms, blocked_flow_l_per_min), 0.05, 0, 100, "L/min",
     "... and flow below this"},
    {WS_KEY(alarms, no_flow_l_per_min), 0.02, 0, 100, "L/min",
     "no flow: valves open but flow below this"},
    {WS_KEY(alarms, tank_low_pct), 15.0, 0, 100, "%", "tank low warning"},
    {WS_KEY(alarms, tank_empty_pct), 3.0, 0, 100, "%",
     "tank empty: spraying stops"},
    {WS_KEY(alarms, modbus_silent_s), 5.0, 0.1, 600, "s",
     "no Modbus answer for this long raises modbus_silent"},
    {WS_KEY(alarms, camera_stall_s), 1.0, 0.05, 60, "s",
     "no frame for this long raises camera_lost"},
    {WS_KEY(alarms, debounce_s), 1.0, 0, 60, "s",
     "a flow/pressure condition must hold this long before it raises an alarm"},
    {WS_KEY(alarms, sensor_fault_hold_s), 0.15, 0, 5, "s",
     "a pressure-sensor fault must last this long before it latches Fault (the pump is off "
     "from the first bad reading)"},
    {WS_KEY(alarms, timing_tolerance_ms), 5.0, 0.5, 100, "ms",
     "while spraying, a valve edge or control-loop cycle later than this, or a missed "
     "pressure-loop period, is a deadline miss that affects spraying"},
    {WS_KEY(alarms, control_overrun_limit), 3, 1, 1000000, "",
     "deadline misses that affect spraying (see timing_tolerance_ms) within one second that "
     "raise control_overruns"},
    {WS_KEY(alarms, calibration_drift_pct), 5.0, 0.5, 50, "%",
     "the line meter's flow and what the calibrated nozzles promise at the commanded duties "
     "(a minute's average of spraying) further apart than this (meter drift, worn nozzles) ..."},
    {WS_KEY(alarms, calibration_drift_hold_s), 30.0, 1, 3600, "s",
     "... for this long raises calibration_drift, a warning: run sprayctl calibrate meter, then "
     "calibrate nozzles"},
    {WS_KEY(alarms, closed_flow_l_per_min), 0.1, 0.02, 2, "L/min",
     "the line meter's flow above this while every valve has been commanded closed for "
     "closed_flow_settle_s (then for debounce_s) raises flow_with_valves_closed, a Fault: a "
     "leaking or stuck-open valve, or a valve wire that no longer closes it"},
    {WS_KEY(alarms, closed_flow_settle_s), 2.0, 1, 30, "s",
     "after the last valve closes, the line drains and the meter's window empties for this long "
     "before flow_with_valves_closed is judged"},
    // [log]
    {WS_KEY(log, dir), std::string(""), 0, 0, "path",
     "as-applied CSV folder (empty = <daemon.state_dir>/as-applied)"},
    {WS_KEY(log, rotate_bytes), 10 * 1024 * 1024, 4096, INT_MAX, "bytes",
     "start a new as-applied file past this size"},
    {WS_KEY(log, keep_files), 150, 1, 10000, "",
     "rotated as-applied files kept (oldest deleted); the default 150 x 10 MB holds about 6 days "
     "of 8 h with 24 nozzles (1.35 kB a record, 5 records a second), so a week's work can be "
     "exported before it goes"},
    {WS_KEY(log, min_free_mb), 64, 0, 1000000, "MB",
     "free space in the as-applied folder's file system under this raises records_disk_full, a "
     "warning that clears itself: spraying goes on; export and delete old files (the default "
     "64 MB holds about 2.5 h of 24 nozzles); 0 = only a failing write raises it. While writes "
     "fail, lines wait in memory (about 10 min of 24 nozzles) and are written once space "
     "returns; beyond that they are dropped and counted (the seq column shows the gap)"},
    // [sim]
    {WS_KEY(sim, speed_profile), std::string("sine"), 0, 0, "",
     "simulated travel speed over time", {"constant", "sine", "ramp"}},
    {WS_KEY(sim, speed_min_m_per_s), 0.5, 0, 10, "m/s",
     "lowest simulated speed (constant uses the maximum)"},
    {WS_KEY(sim, speed_max_m_per_s), 2.5, 0.01, 10, "m/s",
     "highest simulated speed"},
    {WS_KEY(sim, speed_period_s), 20.0, 0.1, 3600, "s",
     "period of the sine/ramp speed profile"},
    {WS_KEY(sim, images_dir), std::string(""), 0, 0, "path",
     "field images (PNG or JPEG files) used as the simulated camera (empty = the bundled ones)"},
    {WS_KEY(sim, images_mm_per_px), 0.0, 0, 100, "mm",
     "ground size of one pixel of images_dir's images: each simulated frame is then the ground "
     "as the [[camera]] sees it (its frame size and ground_mm_per_px), consecutive images "
     "resampled and laid edge to edge; 0 = each image is one frame as it is, of unknown ground "
     "scale (the weed model then takes it squeezed to the model's own input size)"},
    {WS_KEY(sim, seed), 1, 0, INT_MAX, "",
     "random seed of the ideal bench's plant (its nozzle spread and sensor noise); a drawn "
     "machine brings its own"},
    {WS_KEY(sim, wheel_slip_pct), 0.0, -20, 45, "%",
     "the simulated wheel sensor turns this much more than the ground it covers (a driven "
     "wheel spinning > 0, a trailed wheel skidding < 0): its pulses per ground metre are "
     "wheel.pulses_per_metre x (1 + slip), what sprayctl calibrate-wheel measures"},
    {WS_KEY(sim, machine), std::string("drawn"), 0, 0, "",
     "the simulated hydraulic machine: drawn = a realistic one drawn by machine_seed and "
     "machine_index from documented spreads (pump, supply voltage, hose, air chamber, valve "
     "delays, the meter's K error, each nozzle's flow and valve timing, sensor noise), the same "
     "machine for the same pair, as the lab's --plants experiments draw them; ideal = the ideal "
     "bench (one pressure node, smooth pump, linear meter, constant valves). The wheel's slip is "
     "wheel_slip_pct in both; the boom, meter, wheel and sensor scales are the configured ones",
     {"drawn", "ideal"}},
    {WS_KEY(sim, machine_seed), 1, 0, INT_MAX, "",
     "the fleet the drawn machine comes from (the lab's --seed)"},
    {WS_KEY(sim, machine_index), 0, 0, 1000000, "",
     "which machine of that fleet (the lab's --plants machines are 0, 1, ...)"},
    // [fleet]
    {WS_KEY(fleet, enabled), false, 0, 1, "",
     "weedspray-fleet joins this board to the machine over an MQTT broker: it publishes the "
     "daemon's state and forwards the broker's commands as D-Bus calls (docs/fleet.md); the "
     "daemon itself ignores [fleet]"},
    {WS_KEY(fleet, host), std::string("localhost"), 0, 0, "", "the MQTT broker's host"},
    {WS_KEY(fleet, port), 1883, 1, 65535, "",
     "the broker's TCP port (1883 plain, 8883 usually with TLS)"},
    {WS_KEY(fleet, machine), std::string("sprayer"), 0, 0, "",
     "the machine's name, shared by all its boards: topics weedspray/<machine>/<board>/...; "
     "letters, digits, '-' and '_'"},
    {WS_KEY(fleet, board), std::string("board1"), 0, 0, "",
     "this board's name on the machine, unique on it; letters, digits, '-' and '_'"},
    {WS_KEY(fleet, first_nozzle_offset_m), 0.0, -50, 50, "m",
     "this board's first nozzle along the boom: its distance from the boom's left end, looking "
     "forward (the cab draws the boards' nozzles in this order)"},
    {WS_KEY(fleet, keepalive_s), 5, 5, 300, "s",
     "MQTT keep-alive: the broker marks a board whose link went silent lost after 1.5 x this "
     "(a bridge that exits or is killed is marked lost at once)"},
    {WS_KEY(fleet, username), std::string(""), 0, 0, "",
     "the broker user name (empty = anonymous)"},
    {WS_KEY(fleet, password_file), std::string(""), 0, 0, "path",
     "a file whose first line is the broker password (empty = none); readable by the bridge's "
     "user only"},
    {WS_KEY(fleet, tls_cafile), std::string(""), 0, 0, "path",
     "TLS: the CA certificate that signed the broker's (empty = no TLS)"},
    {WS_KEY(fleet, tls_certfile), std::string(""), 0, 0, "path",
     "TLS: this board's client certificate, for brokers that require one (with tls_keyfile)"},
    {WS_KEY(fleet, tls_keyfile), std::string(""), 0, 0, "path",
     "TLS: the client certificate's private key"},
    {WS_KEY(fleet, commands), std::string("operator"), 0, 0, "",
     "the command kinds taken from the broker, as the D-Bus groups split them: none (publish "
     "only), operator (start, stop, set_pressure, clear_alarms), admin (also reload_config); "
     "any other is refused as unauthorised",
     {"none", "operator", "admin"}},
    {WS_KEY(fleet, on_board_lost), std::string("continue"), 0, 0, "",
     "when another board of the machine is lost (its bridge or daemon gone, the broker's last "
     "will), this board sprays on (continue) or stops (stop: the whole boom stops with any "
     "board)",
     {"continue", "stop"}},
    {WS_KEY(fleet, on_broker_lost), std::string("stop"), 0, 0, "",
     "when this board's connection to the broker is lost (so the cab can no longer stop it), it "
     "stops spraying (stop) or sprays on (continue); it reconnects by itself either way",
     {"stop", "continue"}},
    {WS_KEY(fleet, picture_interval_s), 5.0, 0, 3600, "s",
     "how often the bridge publishes camera 0's live-view picture (the daemon's Snapshot: a PNG "
     "with the weed overlay) on weedspray/<machine>/<board>/picture, retained, for the cab page; "
     "0 = never"},
    {WS_KEY(fleet, motion_rate_hz), 0.0, 0, 100, "Hz",
     "how often the bridge publishes this board's ground speed and distance with its daemon's "
     "time stamp on weedspray/<machine>/<board>/motion (QoS 0, not retained) for boards that "
     "take their speed from it; 0 = never (20 on the board that owns the speed)"},
    {WS_KEY(fleet, speed_from), std::string(""), 0, 0, "",
     "the board whose motion topic the bridge hands to this board's daemon (FeedSharedMotion), "
     "for speed.source = \"fleet\"; empty = none"},
    // [cab]
    {WS_KEY(cab, listen_address), std::string("127.0.0.1"), 0, 0, "",
     "weedspray-cab serves the cab page on this address: the cab's network address (or "
     "0.0.0.0) for a phone or tablet; whoever reaches it can start and stop the machine. It "
     "reads the boards from the broker and machine of [fleet]"},
    {WS_KEY(cab, port), 8080, 1, 65535, "", "the cab page's TCP port"},
  });
  // clang-format on
}

}  // namespace weedspray::daemon::key_tables
