// SPDX-License-Identifier: Apache-2.0
// weedspray-lab soak: the command line and the report (text or JSON) of lab/soak.hpp.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "lab/commands.hpp"
#include "lab/soak.hpp"

namespace weedspray::lab {
namespace {

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out + "\"";
}

void print_json(const SoakReport& r) {
  std::printf("{\"minutes\": %.2f, \"seed\": %llu, \"passed\": %s, \"error\": %s,\n",
              r.options.minutes, static_cast<unsigned long long>(r.options.seed),
              r.passed() ? "true" : "false", quoted(r.error).c_str());
  std::printf(
      " \"rss_kb\": {\"after_warmup\": %.0f, \"end\": %.0f, \"max\": %.0f, \"growth\": %.0f},\n",
      r.rss_after_warmup_kb, r.rss_end_kb, r.rss_max_kb, r.rss_growth_kb());
  std::printf(
      " \"cpu_mean_pct\": %.2f, \"control_overruns\": %llu, \"alarms_raised\": %llu, "
      "\"alarms_cleared\": %llu, \"control_overrun_alarms\": %llu,\n",
      r.cpu_mean_pct, static_cast<unsigned long long>(r.control_overruns),
      static_cast<unsigned long long>(r.alarms_raised),
      static_cast<unsigned long long>(r.alarms_cleared),
      static_cast<unsigned long long>(r.unexpected_control_overrun_alarms));
  std::printf(
      " \"volume_l\": {\"log\": %.6f, \"totals\": %.6f, \"plant_true\": %.6f, "
      "\"plant_metered\": %.6f, \"meter_gain\": %.6f, \"log_vs_totals_pct\": %.4f, "
      "\"totals_vs_metered_pct\": %.4f, \"totals_vs_true_pct\": %.4f, "
      "\"raw_totals_vs_true_pct\": %.4f},\n",
      r.log_volume_l, r.totals_volume_l, r.plant_volume_l, r.plant_metered_l, r.plant_meter_gain,
      r.log_vs_totals_pct(), r.totals_vs_metered_pct(), r.totals_vs_plant_pct(),
      r.raw_totals_vs_plant_pct());
  std::printf(
      " \"log\": {\"records\": %llu, \"torn_tail_lines\": %llu, \"damaged_lines\": %llu},\n",
      static_cast<unsigned long long>(r.log_records), static_cast<unsigned long long>(r.torn_lines),
      static_cast<unsigned long long>(r.damaged_lines));
  std::printf(" \"daemon_exit_status\": %d,\n \"timing\": %s,\n \"samples\": [",
              r.daemon_exit_status, r.timing_report.empty() ? "null" : r.timing_report.c_str());
  for (std::size_t i = 0; i < r.samples.size(); ++i) {
    const auto& s = r.samples[i];
    std::printf("%s{\"t_s\": %.1f, \"rss_kb\": %.0f, \"cpu_pct\": %.2f}", i ? ", " : "", s.t_s,
                s.rss_kb, s.cpu_pct);
  }
  std::printf("],\n \"events\": [");
  for (std::size_t i = 0; i < r.events.size(); ++i) {
    const auto& e = r.events[i];
    std::printf(
        "%s\n  {\"t_s\": %.1f, \"kind\": %s, \"expected_alarm\": %s, \"alarm_raised\": %s, "
        "\"alarm_after_ms\": %.0f, \"expects_valves_closed\": %s, \"valves_closed\": %s, "
        "\"resumed\": %s, \"note\": %s}",
        i ? "," : "", e.t_s, quoted(e.kind).c_str(), quoted(e.expected_alarm).c_str(),
        e.alarm_raised ? "true" : "false", e.alarm_after_ms,
        e.expects_valves_closed ? "true" : "false", e.valves_closed ? "true" : "false",
        e.resumed ? "true" : "false", quoted(e.note).c_str());
  }
  std::printf("]}\n");
}

void print_text(const SoakReport& r) {
  std::printf("soak %.1f min, seed %llu: %s%s\n", r.options.minutes,
              static_cast<unsigned long long>(r.options.seed), r.passed() ? "PASSED" : "FAILED",
              r.error.empty() ? "" : (" (" + r.error + ")").c_str());
  std::printf(
      "  RSS after warm-up %.0f kB, end %.0f kB (growth %+.0f kB), max %.0f kB; CPU %.1f %%\n",
      r.rss_after_warmup_kb, r.rss_end_kb, r.rss_growth_kb(), r.rss_max_kb, r.cpu_mean_pct);
  std::printf(
      "  volume: log %.4f L, totals %.4f L, plant metered %.4f L, plant true %.4f L\n"
      "    log-totals %+.3f %%, totals-metered %+.3f %%, totals/meter gain-true %+.3f %% "
      "(raw totals-true %+.3f %%: the meter's K error is %+.2f %%)\n"
      "    %llu records, %llu torn, %llu damaged\n",
      r.log_volume_l, r.totals_volume_l, r.plant_metered_l, r.plant_volume_l, r.log_vs_totals_pct(),
      r.totals_vs_metered_pct(), r.totals_vs_plant_pct(), r.raw_totals_vs_plant_pct(),
      100.0 * (r.plant_meter_gain - 1.0), static_cast<unsigned long long>(r.log_records),
      static_cast<unsigned long long>(r.torn_lines),
      static_cast<unsigned long long>(r.damaged_lines));
  std::printf(
      "  alarms raised %llu, cleared %llu, control_overruns alarms %llu; ControlOverruns "
      "%llu; daemon exit %d\n",
      static_cast<unsigned long long>(r.alarms_raised),
      static_cast<unsigned long long>(r.alarms_cleared),
      static_cast<unsigned long long>(r.unexpected_control_overrun_alarms),
      static_cast<unsigned long long>(r.control_overruns), r.daemon_exit_status);
  for (const auto& e : r.events) {
    std::printf(
        "  %7.1f s %-18s %-22s %s%s%s %s\n", e.t_s, e.kind.c_str(), e.expected_alarm.c_str(),
        e.alarm_raised ? "alarm ok" : "ALARM MISSING",
        e.expects_valves_closed ? (e.valves_closed ? ", valves closed" : ", VALVES OPEN") : "",
        e.resumed ? ", resumed" : ", NOT RESUMED", e.note.c_str());
  }
}

}  // namespace

void add_soak_command(CLI::App& app) {
  auto options = std::make_shared<SoakOptions>();
  auto json = std::make_shared<bool>(false);
  CLI::App* soak = app.add_subcommand(
      "soak",
      "Run weedsprayd --sim on a private bus with faults, reloads and Start/Stop storms injected "
      "at random; report memory, CPU, alarms, misses and whether log, totals and plant volumes "
      "agree (exit status 1 when a bar of the soak is missed)");
  soak->add_option("--minutes", options->minutes, "How long to run")
      ->check(CLI::Range(0.5, 24 * 60.0));
  soak->add_option("--seed", options->seed, "Seed of the event schedule");
  soak->add_option("--event-interval", options->mean_event_interval_s,
                   "Mean seconds between injected events")
      ->check(CLI::Range(5.0, 3600.0));
  soak->add_option("--daemon", options->daemon,
                   "weedsprayd to run (default: the one built beside)");
  soak->add_option("--keep", options->keep_dir, "Keep the run's folder (logs, state) here");
  soak->add_flag("--json", *json, "Print one JSON object instead of text");
  soak->callback([options, json] {
    const SoakReport report = run_soak(*options);
    if (*json) {
      print_json(report);
    } else {
      print_text(report);
    }
    if (!report.passed()) throw CLI::RuntimeError(1);
  });
}

}  // namespace weedspray::lab
