// SPDX-License-Identifier: Apache-2.0
// The D-Bus service org.weedspray.Sprayer1 (sd-bus, one vtable), attached to the main
// thread's sd-event loop, so every callback runs on the main thread without locks.
//   properties: State s, Pressure d, PressureSetpoint d (MPa), DecisionThreshold d, Flow d
//     (L/min), TankLevel d (%),
//     Speed d (m/s), Distance d (m), NozzleDuty ad (%), ZoneDensity ad, Alarms as,
//     VolumeSprayed d (L), AreaCovered d (m^2), SavingsPercent d, ApplicationRate d and
//     TargetRate d (L/ha), FrameRate d (Hz),
//     VisionLatencyMs d, VisionLatencyP99Ms d, ControlOverruns t, Mode s, SpeedSource s,
//     GnssFix s, Position (ddd), GnssSpeed d, Course d, GnssHdop d, GnssSatellites u,
//     GnssTime s, YawRate d (deg/s clockwise), WheelCalibration (tsdtd), Calibration (sds),
//     MeterCalibration (sddd), NozzleCalibration a(sddd), NozzleHealth ad, FlowTrim d,
//     FlowTrimActive b, MeteredOverCalibrated d, RawInputs a(sds) (no change signal)
//     (docs/dbus.md)
//   methods: Start(), Stop(), SetPressureSetpoint(d), SetDecisionThreshold(d),
//     SetTargetRate(d L/ha), ReloadConfig(), ClearAlarms(),
//     InjectSimFault(s) (simulation only), Snapshot(u camera) -> ay PNG (live view, at most
//     2 a second; the reply comes when the camera's next frame is processed),
//     CalibrateWheel(d metres) -> t request (wheel pulses per metre from GNSS over a straight
//     run; the WheelCalibration property reports it), StartCatchTest(d seconds),
//     CalibrateMeter(d litres), CalibrateNozzles(), TestValve(u nozzle, d duty %, d seconds),
//     TestPump(d seconds) (the Calibration property follows them), Motion() -> (d m/s, d m,
//     t ns) (the control loop's latest speed, odometer and time), FeedSharedMotion(d m/s, d m,
//     t ns) (speed.source = "fleet": another board's sample, its clock's time), MotionWithFix()
//     and FeedSharedMotionWithFix(...) (the same with the GNSS fix: d lat, d lon, d heading,
//     u mode 0/2/3, t the fix's time on the owner's clock, x its UTC ns; gnss.source = "fleet"
//     takes it)
//   signals: AlarmRaised(s), AlarmCleared(s)
#pragma once

#include <systemd/sd-bus.h>
#include <systemd/sd-event.h>

#include "daemon/bus/status.hpp"

namespace weedspray::daemon {

class DbusService {
 public:
  // Connects to the system bus (or the session bus), registers the object, takes the name
  // and attaches to `event`; a lost connection calls handler.bus_lost(). Throws
  // std::runtime_error with the sd-bus error.
  DbusService(sd_event* event, bool user_bus, CommandHandler& handler);
  ~DbusService();
  DbusService(const DbusService&) = delete;
  DbusService& operator=(const DbusService&) = delete;

  // Stores the snapshot and emits PropertiesChanged for the properties that differ from the
  // last emitted snapshot. The caller rate-limits (daemon.status_max_rate_hz).
  void update(const Status& status);
  void alarm_raised(const char* name);
  void alarm_cleared(const char* name);

  const Status& status() const { return status_; }

  // sd-bus callbacks (public only so the vtable in the .cpp can name them).
  static int get_property(sd_bus* bus, const char* path, const char* interface,
                          const char* property, sd_bus_message* reply, void* userdata,
                          sd_bus_error* error);
  static int method(sd_bus_message* message, void* userdata, sd_bus_error* error);

 private:
  static int on_disconnected(sd_bus_message* message, void* userdata, sd_bus_error* error);

  sd_bus* bus_ = nullptr;
  sd_bus_slot* slot_ = nullptr;
  sd_bus_slot* disconnected_slot_ = nullptr;
  CommandHandler& handler_;
  Status status_;
  Status emitted_;
  bool emitted_once_ = false;
};

// One method call of org.weedspray.Sprayer1 on `handler`: reads the arguments, calls the
// command, replies. An exception from the handler never crosses sd-bus's C frames: it becomes
// the caller's error reply ("Start failed: ...") and the daemon stays up. Free (no bus of its
// own) so tests and the fuzz target can call it with messages they build.
int handle_method_call(sd_bus_message* message, CommandHandler& handler, sd_bus_error* error);

}  // namespace weedspray::daemon
