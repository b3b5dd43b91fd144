// SPDX-License-Identifier: Apache-2.0
// weedspray-lab soak: runs the sim daemon (weedsprayd --sim) on a private D-Bus session bus for
// a while, injects faults at random through its sim-only InjectSimFault method (sensor open or
// short, camera unplugged, tank sensor silent, refused valve/pump writes), reloads its
// configuration (good and broken), storms it with Start/Stop, and records what a farmer's
// engineer needs to trust a long day: memory and CPU over time, every fault's alarm and whether
// the valves closed, deadline misses, and whether the as-applied log, the totals and the
// plant's true sprayed volume agree.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace weedspray::lab {

struct SoakOptions {
  double minutes = 60;
  std::uint64_t seed = 1;
  double mean_event_interval_s = 30;  // faults/reloads/storms: uniform in [0.5, 1.5] x this
  std::string daemon;                 // weedsprayd to run ("" = beside this tool, or on PATH)
  std::string keep_dir;               // keep the run's folder here ("" = a temp dir, removed)
};

struct SoakSample {
  double t_s = 0;
  double rss_kb = 0;
  double cpu_pct = 0;  // of one core, since the previous sample
};

struct SoakEvent {
  double t_s = 0;
  std::string kind;            // the fault's name, "reload", "reload_broken", "start_stop_storm"
  std::string expected_alarm;  // "" for reloads and storms
  bool alarm_raised = false;   // the expected alarm appeared (or: the daemon kept spraying)
  double alarm_after_ms = -1;
  bool expects_valves_closed = false;  // a fault-class alarm
  bool valves_closed = false;          // State Fault and every NozzleDuty 0 after the alarm
  bool resumed = false;                // spraying again after the repair, ClearAlarms, Start
  std::string note;
};

struct SoakReport {
  SoakOptions options;
  std::vector<SoakSample> samples;
  std::vector<SoakEvent> events;
  double rss_after_warmup_kb = 0;
  double rss_end_kb = 0;
  double rss_max_kb = 0;
  double cpu_mean_pct = 0;
  std::uint64_t control_overruns = 0;  // the D-Bus counter at the end (raw misses + overruns)
  std::uint64_t alarms_raised = 0;     // "alarm raised:" lines in the daemon's log
  std::uint64_t alarms_cleared = 0;
  std::uint64_t unexpected_control_overrun_alarms = 0;
  double log_volume_l = 0;
  double totals_volume_l = 0;
  double plant_volume_l = 0;    // true volume through the nozzles
  double plant_metered_l = 0;   // the plant's meter pulses at the configured pulses/L
  double plant_meter_gain = 1;  // the meter's true pulses/L over the configured one
  std::uint64_t log_records = 0;
  std::uint64_t torn_lines = 0;
  std::uint64_t damaged_lines = 0;
  int daemon_exit_status = -1;
  std::string timing_report;  // the daemon's --timing-report JSON (lateness per loop)
  std::string error;          // set when the soak could not run to its end

  double log_vs_totals_pct() const;
  double totals_vs_metered_pct() const;  // nothing lost between the meter and the totals
  // Totals corrected by the meter's calibration error vs the true volume (the meter error
  // itself is what `calibrate meter` removes; the raw difference is reported too).
  double totals_vs_plant_pct() const;
  double raw_totals_vs_plant_pct() const;
  double rss_growth_kb() const { return rss_end_kb - rss_after_warmup_kb; }
  // The bars: RSS growth <= 1 MB after warm-up, volumes within 0.5 %, every fault
  // alarmed (and the valves closed where it is a fault), a clean exit.
  bool passed() const;
};

SoakReport run_soak(const SoakOptions& options);

}  // namespace weedspray::lab
