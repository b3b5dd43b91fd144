// SPDX-License-Identifier: Apache-2.0
// The calibrations a user ran from the daemon (sprayctl calibrate meter / nozzles), kept in the
// state directory as calibration.toml (written atomically) and preferred over the configured
// values from then on; the configuration stays the fallback:
//   - the flow meter's pulses per litre from a catch test (instead of flow.pulses_per_litre);
//   - each nozzle's line q = A s + b from a duty sweep (instead of the [spray] line), used only
//     when its fit is good enough (R^2 >= calibration.min_r_squared).
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "control/calibration.hpp"
#include "control/spray_rate_law.hpp"

namespace weedspray::daemon {

struct StoredCalibration {
  std::optional<control::FlowMeterCalibration> meter;
  std::vector<std::optional<control::NozzleLineFit>> nozzles;  // index = nozzle
};

// Missing file: nothing stored. A corrupt file: nothing and `error` set (the daemon logs it and
// runs on the configuration).
StoredCalibration load_calibration(const std::filesystem::path& file, std::string* error = nullptr);
// Throws std::runtime_error naming the file.
void save_calibration(const std::filesystem::path& file, const StoredCalibration& calibration);

// Where a value in use came from (the MeterCalibration and NozzleCalibration properties).
enum class LineSource { kConfig, kCalibration, kPoorFit };
const char* to_string(LineSource source) noexcept;

struct NozzleLineChoice {
  control::NozzleLine line{};
  LineSource source = LineSource::kConfig;
  double r_squared = 0.0;  // of the stored fit (0: none)
};

// The line the rate law uses for each of out.size() nozzles: the stored fit when its R^2 is at
// least min_r_squared, else `configured` (kPoorFit says a fit was there but refused).
void choose_nozzle_lines(const control::NozzleLine& configured, const StoredCalibration& stored,
                         double min_r_squared, std::span<NozzleLineChoice> out);

// The flow meter's pulses per litre: the catch test's when there is one, else the configured.
double meter_pulses_per_litre(double configured, const StoredCalibration& stored) noexcept;

}  // namespace weedspray::daemon
