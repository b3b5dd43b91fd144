// SPDX-License-Identifier: Apache-2.0
// What a boom is asked to spray in a field, second by second: each nozzle's share of its
// full-open flow as a weed-density driven rate law would ask for it. Unlike redrawing every
// duty independently each second, a field's demand is
//   - correlated in time: a nozzle crosses a weed patch over several metres (an AR(1) density
//     with correlation time `correlation_s`),
//   - shared across the boom: many patches lie under several nozzles at once (`common_share`
//     of the density's variance is one process for all nozzles),
//   - closed where there is nothing to spray (density below `close_below`: share 0),
//   - interrupted by headlands (every `headland_every_s`, `headland_s` with the boom off),
//   - at a changing speed (`speed_swing` around the nominal over `speed_period_s`).
// A nozzle-health judge that works only when duties are independent and always open fails here.
#pragma once

#include <cstddef>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

namespace weedspray::sim {

struct FieldDutyOptions {
  double correlation_s = 10.0;
  double common_share = 0.5;  // of the density variance, common to every nozzle
  double mean_density = 0.35;
  double density_sd = 0.25;
  double close_below = 0.15;  // density under which the nozzle stays closed
  double min_share = 0.3;     // of full-open flow, at close_below
  double max_share = 0.9;     // at density 1
  double headland_every_s = 120.0;
  double headland_s = 15.0;
  double speed_swing = 0.2;  // +-, of the nominal speed
  double speed_period_s = 360.0;
};

class FieldDutyProcess {
 public:
  FieldDutyProcess(std::size_t nozzles, std::uint64_t seed, FieldDutyOptions options = {});

  // Advances the densities to `t_s` (not before the last call) and writes each nozzle's share
  // of its full-open flow into `shares` (its size: the nozzle count); 0 for a closed nozzle
  // and for every nozzle on a headland.
  void shares_at(double t_s, std::span<double> shares);

  bool headland_at(double t_s) const;
  // The ground speed as a factor of the nominal one.
  double speed_factor_at(double t_s) const;

  const FieldDutyOptions& options() const { return options_; }

 private:
  void advance_to(double t_s);

  FieldDutyOptions options_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  double speed_phase_ = 0;
  double now_s_ = 0;
  double common_ = 0;        // the boom-wide AR(1) state, unit variance
  std::vector<double> own_;  // each nozzle's AR(1) state, unit variance
};

}  // namespace weedspray::sim
