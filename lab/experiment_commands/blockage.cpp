// SPDX-License-Identifier: Apache-2.0
// experiment blockage: per-nozzle health from the one line meter over drawn machines, one
// nozzle partly blocked after a healthy stretch: how soon it is named, how often a healthy one.
#include <string>

#include "lab/experiment_commands/experiment_command.hpp"
#include "lab/experiment_commands/spread_table.hpp"
#include "lab/report/report.hpp"

namespace weedspray::lab {
namespace {

namespace ex = lab::experiments;

Table machine_table() {
  return Table({{"", "machine", 8, "%8zu", ""},
                {"blocked", "blocked", 8, "%8d", ""},
                {"named", "named", 8, "%8d", ""},
                {"detect_s", "after_s", 10, "%10.2f", "%.2f"},
                {"limit_s", "limit_s", 9, "%9.1f", "%.1f"},
                {"false_alarm", "", 0, "", ""},
                {"", "false_alarm", 12, "%12s", ""},
                {"healthy_worst_deviation", "healthy_scatter", 16, "%16.3f", "%.3f"},
                {"healthy_max_evidence", "healthy_evidence", 17, "%17.2f", "%.2f"},
                {"closed_share", "closed", 8, "%8.2f", "%.2f"},
                {"share_lag_correlation", "lag1_r", 8, "%8.2f", "%.2f"},
                {"healthy_rechecks", "rechecks", 9, "%9d", ""},
                {"blocked_ratio", "blocked_ratio", 14, "%14.3f", "%.3f"},
                {"healthy_reading_deviation", "healthy_reading", 16, "%16.3f", "%.3f"}});
}

// As --duties names them.
const char* duties_name(ex::BlockageDuties duties) {
  return duties == ex::BlockageDuties::kField ? "field" : "iid";
}

}  // namespace

int run_blockage_command(const ExperimentOptions& o) {
  const ex::FleetOptions fleet{o.seed, o.plants > 0 ? o.plants : 20, false};
  ex::BlockageOptions options;
  options.duties = o.duties == "iid" ? ex::BlockageDuties::kIid : ex::BlockageDuties::kField;
  if (o.blockage) options.blockage = *o.blockage;
  options.health.judge =
      o.health_judge == "band" ? control::NozzleJudge::kBand : control::NozzleJudge::kCusum;
  options.recheck = o.health_judge == "recheck";
  options.blocked_at_start = o.blocked_at_start;
  const ex::BlockageFleetResult r = ex::run_blockage_fleet(fleet, options);
  Report report;
  report.json()
      .add("judge", Json::string(o.health_judge))
      .add("duties", Json::string(duties_name(options.duties)))
      .add("plants", Json::integer(fleet.plants))
      .add("seed", Json::unsigned_integer(o.seed))
      .add("blockage", Json::number(options.blockage, "%.2f"))
      .add("blocked_at_start", Json::boolean(options.blocked_at_start))
      .add("limit_s", Json::number(options.detect_limit_s, "%.1f"))
      .add("limit", Json::string(options.duties == ex::BlockageDuties::kField
                                     ? "limit_s or the end of the next headland, the later"
                                     : "limit_s"))
      .add("named_within_limit", Json::integer(r.named_within_limit))
      .add("false_alarms", Json::integer(r.false_alarms))
      .add("healthy_minutes", Json::number(r.healthy_minutes, "%.1f"))
      .add("detect_s", spread_json(r.detect_s))
      .add("healthy_worst_deviation", spread_json(r.healthy_worst_deviation))
      .add("healthy_max_evidence", spread_json(r.healthy_max_evidence));
  if (options.recheck)
    report.json().add("healthy_reading_deviation", spread_json(r.healthy_reading_deviation));
  report.line(
      "per-nozzle health from the line meter (%s judge), %d drawn machines (seed %llu), "
      "variable-rate spraying (%s duties) at %.1f MPa / %.0f Hz, staggered, trim on: %.0f s "
      "baseline + %.0f min healthy, then one nozzle %.0f %% blocked%s",
      o.health_judge.c_str(), fleet.plants, static_cast<unsigned long long>(o.seed),
      duties_name(options.duties), options.pressure_mpa, options.frequency_hz,
      options.health.baseline_s, options.blocked_at_start ? 0.0 : options.healthy_s / 60.0,
      options.blockage * 100.0, options.blocked_at_start ? " from the job's start" : "");
  Table machines = machine_table();
  for (std::size_t i = 0; i < r.machines.size(); ++i) {
    const auto& m = r.machines[i];
    machines.row({static_cast<long long>(i + 1), static_cast<long long>(m.blocked_nozzle + 1),
                  static_cast<long long>(m.named_nozzle + 1), m.detect_s, m.limit_s, m.false_alarm,
                  std::string(m.false_alarm ? "YES" : "no"), m.healthy_worst_deviation,
                  m.healthy_max_evidence, m.closed_share, m.share_lag_correlation,
                  static_cast<long long>(m.healthy_rechecks), m.blocked_ratio,
                  m.healthy_reading_deviation});
  }
  report.table(machines, "machines");
  std::string summary = format_text(
      "named within %.0f s or the next headland's end: %d of %d; false alarms: %d in %.0f healthy "
      "machine-minutes; "
      "time to name: mean %.2f s, sd %.2f, worst %.2f; healthy scatter (largest |ratio - 1|): "
      "mean %.3f, worst %.3f",
      options.detect_limit_s, r.named_within_limit, fleet.plants, r.false_alarms, r.healthy_minutes,
      r.detect_s.mean, r.detect_s.sd, r.detect_s.worst, r.healthy_worst_deviation.mean,
      r.healthy_worst_deviation.worst);
  if (options.recheck) {
    const control::NozzleRecheckConfig& c = options.recheck_config;
    summary += format_text(
        "; healthy re-check readings (largest |reading - 1| per machine, alarm from %.3f): mean "
        "%.3f, worst %.3f",
        c.alarm_fraction - c.tolerance, r.healthy_reading_deviation.mean,
        r.healthy_reading_deviation.worst);
  } else if (options.health.judge == control::NozzleJudge::kCusum) {
    summary += format_text(
        "; healthy evidence (largest, alarm above %.0f): mean %.2f, sd %.2f, worst %.2f",
        options.health.alarm_threshold, r.healthy_max_evidence.mean, r.healthy_max_evidence.sd,
        r.healthy_max_evidence.worst);
  }
  report.lines({summary});
  report.print(o.json);
  return 0;
}

}  // namespace weedspray::lab
