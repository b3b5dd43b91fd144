// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/alarm_catalog.hpp"

#include <array>
#include <sstream>

namespace weedspray::daemon {
namespace {

// In AlarmId order (alarms.hpp); the test walks every id.
constexpr std::array<AlarmCatalogEntry, kAlarmCount> kCatalog = {{
    {"0c23547c31b64bdb87fd79b897d25ccb",
     "The line pressure went above alarms.over_pressure_mpa; the pressure loop switched the pump "
     "off and opened the return valve in the same cycle.",
     "Look for a closed or blocked boom section, a stuck return valve or a set-point too close to "
     "the trip. Clear the alarms once the pressure is back below the trip."},
    {"6f28571a2c6746e198c507f3265366f3",
     "The pressure sensor's loop current is outside alarms.sensor_fault_low_ma.."
     "sensor_fault_high_ma (a cut or shorted wire, a dead sensor) or its converter stopped "
     "delivering samples; the pressure loop switched the pump off and closed the valves in the "
     "cycle that read it.",
     "Check the sensor's wiring and supply (4-20 mA loop, shunt, ADC or Modbus module); "
     "`sprayctl status` shows the current read. Clear the alarms once the reading is good."},
    {"05aeac547b0b4f5f9cba88766b3e6b63",
     "High pressure with little flow while the pump runs and valves are open: the line or the "
     "nozzles are blocked.",
     "Clean the line filter and the nozzles' strainers and tips; check that the section valves "
     "open. Clear the alarms, then spray again."},
    {"3a34b8ef9c6442a397cee3cb26072087",
     "Normal or low pressure but no flow while the pump runs and valves are open: the pump does "
     "not deliver, the tank is empty or the flow meter does not count.",
     "Check the tank, the suction side and the pump; check the flow meter's wiring "
     "(`sprayctl status` shows its pulses). Clear the alarms, then spray again."},
    {"530084933dc44306b588e9993d24a47b", "The tank level is under alarms.tank_low_pct.",
     "Refill soon; spraying goes on."},
    {"6631b62995a2422891e98fc04a9b8ea2",
     "The tank level is under alarms.tank_empty_pct: the pump would run dry.",
     "Refill the tank, then clear the alarms."},
    {"169961ae78d24ceab41c8604b6fe6c15",
     "The Modbus tank-level sensor has not answered for alarms.modbus_silent_s.",
     "Check the RS-485 wiring, termination, the sensor's supply, its address and baud rate "
     "(`[tank]` in the configuration)."},
    {"bd403bf37cf14151bbc2e8e1542c45a2",
     "A camera delivered no frame for alarms.camera_stall_s: its nozzles spray blind or not at "
     "all.",
     "Check the camera's cable and USB/CSI connection and that its device node exists; the "
     "journal names the camera. Clear the alarms once frames arrive."},
    {"01fcec572bfe417299eb4b7af449ede5",
     "The frames do not cover the ground at this speed, or the weed map arrives after the "
     "nozzles have passed the ground it shows.",
     "Drive slower, lower the camera's frame size or use a lighter weed source or model "
     "(`weedspray-lab bench-vision` gives the time per frame)."},
    {"43fc840339f4479b89415ff12c83baed",
     "The real-time loops missed more than alarms.control_overrun_limit deadlines in the last "
     "second while spraying: valve timing is off.",
     "Check for other load on the board, CPU throttling (temperature, power supply) and that "
     "the daemon runs with its real-time priorities (docs/install.md)."},
    {"07e8a38a3ccf40c4aa9e1ba2079b319d",
     "A camera's weed model fails at run time; that camera's nozzles stay closed until its "
     "frames are processed again.",
     "Check the model file and its JSON (`weedsprayd --check-config` loads it); the journal "
     "names the camera and the error."},
    {"b46357a2916e488e9751a252c6a0b812",
     "An output refused a write (a GPIO line, the pump relay, the return-valve DAC, the buzzer "
     "or lamp): a valve may be stuck open; every other output was driven safe and the heartbeat "
     "stopped.",
     "Check the named output's wiring, driver board and supply; the journal names the line. "
     "Clear the alarms once it writes again."},
    {"021d44e3142649e7ad716479f5a05881",
     "GNSS is enabled but gpsd has had no usable fix for gnss.lost_fix_timeout_s; the speed "
     "falls back as configured (wheel pulses, else the fixed speed).",
     "Check the antenna's view of the sky and gpsd (`gpsmon`); spraying goes on with the "
     "fallback speed."},
    {"f7154c8cecdb4920aceb4d3979e5b77b",
     "One nozzle's flow is off its learnt baseline: blocked (low) or worn or stuck open (high).",
     "Clean or replace the named nozzle's tip and strainer; check its valve. Clear the alarms "
     "afterwards."},
    {"7e621d51e1984a65a17ba872e179402c",
     "The line meter and the calibrated nozzles have disagreed by more than "
     "alarms.calibration_drift_pct for alarms.calibration_drift_hold_s: meter drift, worn or "
     "blocked nozzles, or no calibration yet.",
     "Run `sprayctl calibrate meter`, then `sprayctl calibrate nozzles`."},
    {"73c2331d54944a8781e6ca9dcdf9ddba",
     "Liquid flows through the meter while every valve is commanded closed: a valve leaks, "
     "sticks open or its wire does not close it.",
     "Find the leaking valve (the boom drips there), clean or replace it and check its driver "
     "wiring; clear the alarms afterwards."},
    {"bbaeb950129e4e379fedf407786028ec",
     "The emergency-stop circuit opened: valves and pump were written safe on the E-stop's own "
     "thread and stay safe until the circuit is closed and the alarms are cleared.",
     "Find why it was pressed or why the circuit opened (a broken wire looks the same); close "
     "it, then `sprayctl clear-alarms`."},
    {"2f9125fdd7924f8f9e726a966a6dd214",
     "As-applied lines could not be written, or free space in the log folder is under "
     "log.min_free_mb; the lines wait in memory and spraying goes on.",
     "Export and delete old as-applied files (or give the log folder more space); the alarm "
     "clears itself once the waiting lines are written."},
    {"b5a85ee395a94b8db98523467f2b3086",
     "The exit watcher (weedspray-safe-outputs --when-closed, the process that writes the "
     "outputs safe within milliseconds if the daemon is killed) ended and could not be started "
     "again, or each new one ends as soon as it starts: after a kill -9 only ExecStopPost "
     "would close the valves, seconds later.",
     "Look in the journal for why the watcher ended or could not start (a missing or broken "
     "weedspray-safe-outputs, memory); reinstall the package or restart the service. Clear the "
     "alarms once a watcher runs again."},
    {"5d0f5b0e8c6a4f4e9a43c1d7e2b86a19",
     "speed.source = \"fleet\": no speed sample from the owning board (fleet.speed_from) for "
     "speed.shared_timeout_s: that board, its bridge, the broker or this board's bridge is gone, "
     "so this board no longer knows where its nozzles are; the control loop closed every valve "
     "in the cycle that found it.",
     "Check the owning board's daemon and bridge, the broker and this board's bridge "
     "(`systemctl status weedspray-fleet`; the journal says when the broker connection "
     "closed). Once `SpeedSource` reads \"fleet\" again, clear the alarms and start."},
    {"f3c2511bf1674c00bded4c9903d9cae5",
     "The headland re-check held a nozzle open alone and read it off its calibrated held-open "
     "flow by nozzle_health.recheck_warn_pct or more (a partly blocked, worn or damaged tip); "
     "its line has been rescaled by the reading, so the dose holds meanwhile. Off by "
     "nozzle_health.recheck_alarm_pct it is nozzle_flow_fault too. The warning clears when "
     "the nozzle reads within its calibration again.",
     "Look at the named nozzle at the next stop: clean its tip and strainer or replace it, then "
     "run `sprayctl calibrate nozzles` (its new calibration is the new reference)."},
}};

}  // namespace

const AlarmCatalogEntry& alarm_catalog_entry(AlarmId id) noexcept {
  return kCatalog[static_cast<std::size_t>(id)];
}

std::string_view alarm_severity(AlarmId id) noexcept {
  return is_fault(id) ? "fault" : "warning";
}

std::string journal_catalog() {
  std::ostringstream out;
  out << "# weedspray's alarms for journalctl -x (generated by weedsprayd "
         "--print-alarm-catalog=journal)\n";
  for (std::size_t i = 0; i < kAlarmCount; ++i) {
    const auto id = static_cast<AlarmId>(i);
    const AlarmCatalogEntry& e = alarm_catalog_entry(id);
    out << "\n-- " << e.message_id << "\n"
        << "Subject: alarm " << alarm_name(id) << " (" << alarm_severity(id) << ")\n"
        << "Defined-By: weedspray\n"
        << "Documentation: man:weedsprayd(8)\n\n"
        << e.meaning << "\n\n"
        << (is_fault(id) ? "A fault: the sprayer is in Fault, valves closed and pump off, until "
                           "the alarms are cleared.\n\n"
                         : "")
        << "What to do: " << e.remedy << "\n";
  }
  return out.str();
}

std::string alarm_catalog_markdown() {
  std::ostringstream out;
  out << "# Alarms\n\n"
      << "Generated by `weedsprayd --print-alarm-catalog=markdown`. A **fault** puts the sprayer "
         "in Fault (valves closed, pump off, the heartbeat stopped) until `sprayctl "
         "clear-alarms`; a **warning** is reported and spraying goes on. `sprayctl status` and "
         "the D-Bus property `AlarmDetails` show each latched alarm with its severity, whether "
         "its condition is still present, and what to do; in the journal each alarm carries "
         "its `MESSAGE_ID`, so `journalctl -x -u weedsprayd` prints the same text.\n\n"
      << "| alarm | severity | meaning | what to do |\n|---|---|---|---|\n";
  for (std::size_t i = 0; i < kAlarmCount; ++i) {
    const auto id = static_cast<AlarmId>(i);
    const AlarmCatalogEntry& e = alarm_catalog_entry(id);
    out << "| `" << alarm_name(id) << "` | " << alarm_severity(id) << " | " << e.meaning << " | "
        << e.remedy << " |\n";
  }
  return out.str();
}

}  // namespace weedspray::daemon
