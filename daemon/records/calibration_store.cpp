// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/calibration_store.hpp"

#include <toml++/toml.h>
#include <cmath>
#include <sstream>
#include <system_error>

#include "daemon/records/atomic_file.hpp"

namespace weedspray::daemon {

StoredCalibration load_calibration(const std::filesystem::path& file, std::string* error) {
  StoredCalibration stored;
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return stored;
  try {
    const toml::table table = toml::parse_file(file.string());
    if (const toml::table* meter = table["meter"].as_table()) {
      control::FlowMeterCalibration m;
      m.pulses_per_litre = (*meter)["pulses_per_litre"].value_or(0.0);
      m.configured_pulses_per_litre = (*meter)["configured_pulses_per_litre"].value_or(0.0);
      m.error_pct = (*meter)["error_pct"].value_or(0.0);
      if (std::isfinite(m.pulses_per_litre) && m.pulses_per_litre > 0) stored.meter = m;
    }
    if (const toml::array* nozzles = table["nozzle"].as_array()) {
      for (const toml::node& node : *nozzles) {
        const toml::table* n = node.as_table();
        if (n == nullptr) continue;
        const std::int64_t index = (*n)["index"].value_or(std::int64_t{-1});
        if (index < 0 || index >= 32) continue;
        control::NozzleLineFit fit;
        fit.line.slope_l_per_min_per_pct = (*n)["slope_l_per_min_per_pct"].value_or(0.0);
        fit.line.intercept_l_per_min = (*n)["intercept_l_per_min"].value_or(0.0);
        fit.line.calibration_pressure_mpa = (*n)["pressure_mpa"].value_or(0.0);
        // Absent in older files (and when not measured): unknown.
        const double full_open = (*n)["full_open_flow_l_per_min"].value_or(0.0);
        fit.line.full_open_flow_l_per_min =
            std::isfinite(full_open) && full_open > 0 ? full_open : 0.0;
        fit.r_squared = (*n)["r_squared"].value_or(0.0);
        fit.residual_rms_l_per_min = (*n)["residual_rms_l_per_min"].value_or(0.0);
        fit.points_used = static_cast<std::size_t>((*n)["points"].value_or(std::int64_t{0}));
        const auto i = static_cast<std::size_t>(index);
        if (stored.nozzles.size() <= i) stored.nozzles.resize(i + 1);
        stored.nozzles[i] = fit;
      }
    }
  } catch (const toml::parse_error& e) {
    if (error != nullptr) {
      *error = file.string() + ":" + std::to_string(e.source().begin.line) + ": " +
               std::string(e.description());
    }
    return StoredCalibration{};
  }
  return stored;
}

void save_calibration(const std::filesystem::path& file, const StoredCalibration& calibration) {
  toml::table table;
  if (calibration.meter) {
    table.insert("meter", toml::table{{"pulses_per_litre", calibration.meter->pulses_per_litre},
                                      {"configured_pulses_per_litre",
                                       calibration.meter->configured_pulses_per_litre},
                                      {"error_pct", calibration.meter->error_pct}});
  }
  toml::array nozzles;
  for (std::size_t i = 0; i < calibration.nozzles.size(); ++i) {
    const auto& fit = calibration.nozzles[i];
    if (!fit) continue;
    nozzles.push_back(toml::table{{"index", static_cast<std::int64_t>(i)},
                                  {"slope_l_per_min_per_pct", fit->line.slope_l_per_min_per_pct},
                                  {"intercept_l_per_min", fit->line.intercept_l_per_min},
                                  {"pressure_mpa", fit->line.calibration_pressure_mpa},
                                  {"full_open_flow_l_per_min", fit->line.full_open_flow_l_per_min},
                                  {"r_squared", fit->r_squared},
                                  {"residual_rms_l_per_min", fit->residual_rms_l_per_min},
                                  {"points", static_cast<std::int64_t>(fit->points_used)}});
  }
  if (!nozzles.empty()) table.insert("nozzle", std::move(nozzles));
  std::ostringstream text;
  text << "# Written by weedsprayd (sprayctl calibrate meter / nozzles); delete to fall back to\n"
          "# the configuration.\n"
       << table << "\n";
  write_file_atomically(file, text.str());
}

const char* to_string(LineSource source) noexcept {
  switch (source) {
    case LineSource::kCalibration:
      return "calibration";
    case LineSource::kPoorFit:
      return "config (poor fit)";
    case LineSource::kConfig:
      break;
  }
  return "config";
}

void choose_nozzle_lines(const control::NozzleLine& configured, const StoredCalibration& stored,
                         double min_r_squared, std::span<NozzleLineChoice> out) {
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = NozzleLineChoice{configured, LineSource::kConfig, 0.0};
    if (i >= stored.nozzles.size() || !stored.nozzles[i]) continue;
    const control::NozzleLineFit& fit = *stored.nozzles[i];
    out[i].r_squared = fit.r_squared;
    const bool usable = fit.line.slope_l_per_min_per_pct > 0 &&
                        fit.line.calibration_pressure_mpa > 0 && fit.r_squared >= min_r_squared;
    if (!usable) {
      out[i].source = LineSource::kPoorFit;
      continue;
    }
    // With this nozzle's own full-open flow when the sweep metered it held open (0 = unknown:
    // the configured one belongs to the configured line, not to this nozzle).
    out[i].line = fit.line;
    out[i].source = LineSource::kCalibration;
  }
}

double meter_pulses_per_litre(double configured, const StoredCalibration& stored) noexcept {
  return stored.meter ? stored.meter->pulses_per_litre : configured;
}

}  // namespace weedspray::daemon
