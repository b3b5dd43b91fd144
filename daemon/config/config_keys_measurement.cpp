// SPDX-License-Identifier: Apache-2.0
// The configuration keys of [calibration], [nozzle_health], [wheel], [speed], [gnss], [turn],
// [modbus]: what the machine measures.
#include <climits>

#include "daemon/config/config_key_tables.hpp"

// GCC 12 reports a false -Wmaybe-uninitialized inside std::variant<..., std::string> when the
// key table is built (GCC bug 107138 and relatives); the table is plain constant data.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace weedspray::daemon::key_tables {

void append_measurement_keys(std::vector<KeySpec<Config>>& keys) {
  // clang-format off
  keys.insert(keys.end(), {
    // [calibration]
    {WS_KEY(calibration, duties_pct), std::vector<double>{20.0, 40.0, 60.0, 80.0}, 1, 99, "%",
     "sprayctl calibrate nozzles: each nozzle alone at each of these duties (at least 2 "
     "different; the line q = A s + b is fitted between the lowest and the highest)"},
    {WS_KEY(calibration, settle_s), 2.0, 0, 60, "s",
     "time skipped at each point of the sweep while valve, pressure and meter settle"},
    {WS_KEY(calibration, measure_s), 5.0, 0.2, 600, "s",
     "time the meter is counted at each point (the pulses per point: measure_s x K x flow; "
     "5 s of one nozzle at 20 % gives ~200 pulses at 8500 pulses/L)"},
    {WS_KEY(calibration, min_r_squared), 0.98, 0, 1, "",
     "a nozzle whose fitted line has R^2 below this keeps the [spray] line (a sticking valve, a "
     "meter too coarse for one nozzle)"},
    {WS_KEY(calibration, meter_max_change_pct), 25.0, 1, 100, "%",
     "sprayctl calibrate meter --volume: a result further than this from flow.pulses_per_litre "
     "is refused as a likely typo in the volume (the catch test still awaits the right one); "
     "a meter that truly differs that much needs flow.pulses_per_litre set"},
    {WS_KEY(calibration, full_open), true, 0, 1, "",
     "sprayctl calibrate nozzles: also meter each nozzle held open (100 %, one point more): a "
     "request at or above that flow holds the valve open, and the flow trim and "
     "calibration_drift then judge windows with held-open nozzles too (without it they wait "
     "for windows without any)"},
    // [nozzle_health]
    {WS_KEY(nozzle_health, enabled), false, 0, 1, "",
     "judge each nozzle's flow from the line meter while spraying (staggered PWM phases make "
     "the nozzles separable) and raise nozzle_flow_fault naming a blocked or over-flowing one"},
    {WS_KEY(nozzle_health, baseline_s), 60.0, 1, 3600, "s",
     "spraying time over which each nozzle's flow is learned as its baseline"},
    {WS_KEY(nozzle_health, time_constant_s), 6.0, 0.5, 600, "s",
     "forgetting time of the running per-nozzle estimate (the ratios shown; band: judged)"},
    {WS_KEY(nozzle_health, judge), std::string("band"), 0, 0, "",
     "band: a nozzle whose ratio is off 1 by alarm_fraction for alarm_hold_s is a fault; cusum: "
     "the evidence that one nozzle's flow changed by alarm_fraction, summed over the meter's "
     "windows (faster on the lab's varied duties, but it false-alarms on a field's correlated "
     "duties and on the daemon's simulator: the valves' unequal opening and closing delays make "
     "the flow per commanded second depend on the duty; figures: weedspray-lab experiment "
     "blockage, docs/benchmarks.md)",
     {"band", "cusum"}},
    {WS_KEY(nozzle_health, alarm_fraction), 0.12, 0.01, 0.99, "",
     "band: a nozzle whose flow / baseline is off 1 by more than this is a fault...; cusum: the "
     "change of one nozzle's flow, as a fraction of its baseline, looked for..."},
    {WS_KEY(nozzle_health, alarm_hold_s), 1.0, 0, 600, "s", "band: ...once it lasted this long"},
    {WS_KEY(nozzle_health, alarm_threshold), 24.0, 1, 1000, "",
     "cusum: ...named once its evidence (log-likelihood ratio) exceeds this: higher, fewer false "
     "alarms and later names (24: about 1 false alarm in 10^5 machine-minutes on the lab's "
     "fleet)"},
    {WS_KEY(nozzle_health, recheck), true, 0, 1, "",
     "off crop or stopped (nothing to spray for recheck_clear_s, no crop seen under the boom or "
     "the vehicle stopped), hold each nozzle open alone and read it against its calibrated "
     "held-open flow (sprayctl calibrate nozzles): its line is rescaled by the reading, a "
     "nozzle off by recheck_warn_pct is named in the journal and on the bus, one off by "
     "recheck_alarm_pct raises nozzle_flow_fault; runs only once every nozzle has a metered "
     "held-open flow and the flow meter is wired"},
    {WS_KEY(nozzle_health, recheck_clear_s), 2.0, 0.1, 60, "s",
     "nothing to spray (and no crop under the boom, or stopped) for this long opens the window"},
    {WS_KEY(nozzle_health, recheck_settle_s), 1.0, 0.2, 10, "s",
     "each nozzle held open alone this long before it is read (valve, line, pressure loop)"},
    {WS_KEY(nozzle_health, recheck_measure_s), 2.0, 0.5, 30, "s",
     "then read against the meter this long"},
    {WS_KEY(nozzle_health, recheck_interval_s), 60.0, 0, 3600, "s",
     "a whole-boom re-check starts at most this often (0: at every window)"},
    {WS_KEY(nozzle_health, recheck_warn_pct), 5.0, 2, 50, "%",
     "a nozzle whose reading is off its calibration by this much is named as a warning (both "
     "limits less 1.5 %, the reading's own uncertainty)"},
    {WS_KEY(nozzle_health, recheck_alarm_pct), 10.0, 3, 90, "%",
     "...and by this much raises nozzle_flow_fault naming it"},
    {WS_KEY(nozzle_health, recheck_stopped_m_per_s), 0.05, 0, 1, "m/s",
     "below this ground speed the vehicle counts as stopped (a re-check may run over crop)"},
    // [wheel]
    {WS_KEY(wheel, source), std::string("pulses"), 0, 0, "",
     "speed from the Hall wheel sensor, or a fixed speed", {"pulses", "fixed"}},
    {WS_KEY(wheel, pulses_per_metre), 100.0, 0.1, 1e5, "pulses/m",
     "wheel sensor constant"},
    {WS_KEY(wheel, fixed_speed_m_per_s), 1.0, 0, 10, "m/s",
     "speed assumed when source = \"fixed\""},
    // [speed]
    {WS_KEY(speed, source), std::string("wheel"), 0, 0, "",
     "the ground speed of the rate law: \"wheel\" as [wheel] says (its pulses, or its fixed "
     "speed), \"gnss\" the receiver's speed over ground ([gnss] enabled; the wheel's pulses stay "
     "the distance base when wheel.source = \"pulses\"; without a usable fix the speed falls back "
     "to the wheel's pulses, else wheel.fixed_speed_m_per_s), \"fixed\" wheel.fixed_speed_m_per_s, "
     "\"fleet\" another board's speed and distance over the broker (fleet.speed_from; both the "
     "speed and the distance base, the wheel unused)",
     {"wheel", "fixed", "gnss", "fleet"}},
    {WS_KEY(speed, shared_timeout_s), 0.5, 0.1, 2.0, "s",
     "speed.source = \"fleet\": no sample from the owning board for this long closes every "
     "valve and raises shared_speed_lost (at 2.5 m/s, 0.5 s is 1.25 m travelled on an old "
     "speed)"},
    // [gnss]
    {WS_KEY(gnss, enabled), false, 0, 1, "",
     "take position, speed and course: from gpsd (the receiver is gpsd's: NMEA, u-blox, RTK) "
     "or, with gnss.source = \"fleet\", from another board"},
    {WS_KEY(gnss, source), std::string("gpsd"), 0, 0, "",
     "where the fix comes from: \"gpsd\" this board's receiver, \"fleet\" the fix the board "
     "fleet.speed_from publishes with its motion (speed.source = \"fleet\"; the antenna keys "
     "then say where that board's antenna sits relative to this board's nozzles)",
     {"gpsd", "fleet"}},
    {WS_KEY(gnss, host), std::string("localhost"), 0, 0, "", "gpsd's host"},
    {WS_KEY(gnss, port), 2947, 1, 65535, "", "gpsd's TCP port"},
    {WS_KEY(gnss, lost_fix_timeout_s), 2.0, 0.2, 60, "s",
     "no 2D/3D fix for this long raises gnss_fix_lost (and a receiver reporting no fix makes "
     "speed.source = \"gnss\" fall back at once)"},
    {WS_KEY(gnss, first_fix_timeout_s), 60.0, 1, 3600, "s",
     "after start, no usable fix for this long raises gnss_fix_lost (a receiver's cold start "
     "takes 30-60 s); afterwards lost_fix_timeout_s applies"},
    {WS_KEY(gnss, reconnect_max_s), 5.0, 0.1, 600, "s",
     "while gpsd is away, reconnection attempts back off from 0.25 s up to this"},
    {WS_KEY(gnss, antenna_ahead_of_nozzles_m), 0.0, -50, 50, "m",
     "the antenna's distance ahead of the nozzle line along the direction of travel (negative: "
     "behind it); maps place each nozzle's patch from the antenna's position and course"},
    {WS_KEY(gnss, antenna_right_of_centre_m), 0.0, -50, 50, "m",
     "the antenna's distance right of the boom's centre, looking forward (negative: left)"},
    // [turn]
    {WS_KEY(turn, compensation), true, 0, 1, "",
     "on a curve give each nozzle the rate and schedule of its own ground speed, v + yaw rate x "
     "its lateral offset (nozzle 0 is the leftmost, looking forward); needs a yaw source"},
    {WS_KEY(turn, yaw_source), std::string("gnss"), 0, 0, "",
     "where the yaw rate comes from: \"gnss\" the rate of change of the receiver's course "
     "([gnss] enabled), \"imu\" a gyro through IIO (turn.imu_device), \"none\" "
     "no turn compensation",
     {"gnss", "none", "imu"}},
    {WS_KEY(turn, imu_device), std::string(""), 0, 0, "",
     "yaw_source = \"imu\": the IIO gyro (e.g. MPU-6050 with inv_mpu6050, LSM6DS3 with "
     "st_lsm6dsx): \"iio:deviceN\", its directory, or its name; read at 100 Hz from "
     "in_anglvel_<axis>_raw x its scale"},
    {WS_KEY(turn, imu_axis), std::string("z"), 0, 0, "",
     "the gyro axis that is vertical on the machine", {"x", "y", "z"}},
    {WS_KEY(turn, imu_axis_up), true, 0, 1, "",
     "that axis points up (IIO's right-hand rule: a left turn is positive about an up axis); "
     "false when the sensor is mounted with it pointing down"},
    {WS_KEY(turn, min_speed_m_per_s), 0.3, 0, 5, "m/s",
     "below this ground speed the course over ground is noise: the yaw rate is taken as 0"},
    {WS_KEY(turn, yaw_filter_s), 0.5, 0, 10, "s",
     "time constant of the yaw rate's low-pass filter (0 = none)"},
    // [modbus]
    {WS_KEY(modbus, enabled), false, 0, 1, "",
     "read the tank level from a Modbus RTU sensor"},
    {WS_KEY(modbus, device), std::string("/dev/ttyUSB0"), 0, 0, "path",
     "RS-485 serial device"},
    {WS_KEY(modbus, baud), 9600, 1200, 921600, "baud", "serial speed"},
    {WS_KEY(modbus, parity), std::string("N"), 0, 0, "", "serial parity",
     {"N", "E", "O"}},
    {WS_KEY(modbus, slave_id), 1, 1, 247, "", "Modbus slave address"},
    {WS_KEY(modbus, tank_register), 0, 0, 65535, "",
     "holding register with the tank level"},
    {WS_KEY(modbus, tank_scale_pct_per_count), 0.1, 1e-6, 100,
     "% per count", "tank level = register value x this"},
    {WS_KEY(modbus, poll_period_s), 1.0, 0.05, 60, "s", "polling period"},
    {WS_KEY(modbus, timeout_s), 0.5, 0.01, 10, "s", "response timeout"},
  });
  // clang-format on
}

}  // namespace weedspray::daemon::key_tables
