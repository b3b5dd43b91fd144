// SPDX-License-Identifier: Apache-2.0
// experiment field-dose: the boom-total dose error (L/ha) over a field run with speed changes,
// over drawn machines calibrated as made, then changed; the online trim on and off.
#include "lab/experiment_commands/experiment_command.hpp"
#include "lab/experiment_commands/spread_table.hpp"
#include "lab/report/report.hpp"

namespace weedspray::lab {
namespace {

namespace ex = lab::experiments;

Table field_dose_machine_table() {
  return Table({{"", "machine", 8, "%8zu", ""},
                {"target_l_per_ha", "target_L/ha", 12, "%12.1f", "%.2f"},
                {"applied_l_per_ha", "applied_L/ha", 13, "%13.1f", "%.2f"},
                {"error_pct", "error%", 8, "%8.2f", "%.3f"},
                {"law_error_pct", "vs_law%", 8, "%8.2f", "%.3f"},
                {"trim_off_error_pct", "off_err%", 9, "%9.2f", "%.3f"},
                {"raised_share_pct", "raised%", 8, "%8.2f", "%.2f"},
                {"held_open_share_pct", "held%", 7, "%7.2f", "%.2f"},
                {"meter_drift_pct", "drift%", 7, "%7.2f", "%.2f"},
                {"band_low_share", "band_lo", 8, "%8.2f", "%.3f"},
                {"band_high_share", "band_hi", 8, "%8.2f", "%.3f"}});
}

}  // namespace

int run_field_dose_command(const ExperimentOptions& o) {
  const ex::FleetOptions fleet{o.seed, o.plants > 0 ? o.plants : 20, true};
  const ex::FieldDoseOptions options;
  const ex::FieldDoseFleetResult r = ex::run_field_dose_fleet(fleet, options);
  Report report = fleet_report(fleet.plants, o.seed);
  report.json()
      .add("changed_after_calibration", Json::boolean(true))
      .add("run_s", Json::number(options.run_s, "%.0f"))
      .add("min_share", Json::number(options.field.min_share, "%.2f"))
      .add("max_share", Json::number(options.field.max_share, "%.2f"))
      .add("target_follows_speed", Json::boolean(true))
      .add("speed_swing", Json::number(options.field.speed_swing, "%.2f"));
  report.line(
      "boom-total dose over a %.0f s field (shares %.2f-%.2f of full flow, speed +-%.0f %%, "
      "headlands) at %.1f MPa / %.0f Hz, the daemon's band %.0f-%.0f %% (%s), %d drawn machines "
      "(seed %llu), each calibrated as made, then changed",
      options.run_s, options.field.min_share, options.field.max_share,
      options.field.speed_swing * 100.0, options.pressure_mpa, options.frequency_hz,
      options.law.min_duty_pct, options.law.max_duty_pct,
      options.law.low_duty_policy == control::LowDutyPolicy::kRaiseToMin ? "raise_to_min" : "close",
      fleet.plants, static_cast<unsigned long long>(o.seed));
  Table machines = field_dose_machine_table();
  for (std::size_t i = 0; i < r.machines.size(); ++i) {
    const ex::FieldDoseMachine& m = r.machines[i];
    machines.row({static_cast<long long>(i + 1), m.trim_on.target_l_per_ha,
                  m.trim_on.applied_l_per_ha, m.trim_on.error_pct, m.trim_on.law_error_pct,
                  m.trim_off.error_pct, m.trim_on.raised_share_pct, m.trim_on.held_open_share_pct,
                  m.change.meter_drift * 100.0, m.trim_on.band_low_share,
                  m.trim_on.band_high_share});
  }
  report.table(machines, "machines");
  SpreadTable table("over the machines");
  for (const auto* row : {&r.trim_on, &r.trim_off}) {
    const bool on = row == &r.trim_on;
    table.section(on ? "trim_on" : "trim_off", on ? "online flow trim ON" : "online flow trim OFF")
        .row("error_pct", "dose error [%] (worst: largest size)", row->error_pct, "%12.3f")
        .row("abs_error_pct", "|dose error| [%]", row->abs_error_pct, "%12.3f")
        .row("law_error_pct", "vs the band's decision [%]", row->law_error_pct, "%12.3f")
        .row("raised_share_pct", "nozzle-time raised to duty_min [%]", row->raised_share_pct,
             "%12.2f")
        .row("held_open_share_pct", "nozzle-time held open [%]", row->held_open_share_pct, "%12.2f")
        .row("applied_l_per_ha", "applied [L/ha]", row->applied_l_per_ha, "%12.1f")
        .row("clipped_pct", "clipped above full open [%]", row->clipped_pct, "%12.3f");
  }
  table.report_to(report);
  report.print(o.json);
  return 0;
}

}  // namespace weedspray::lab
