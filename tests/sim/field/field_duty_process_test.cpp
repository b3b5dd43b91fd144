// SPDX-License-Identifier: Apache-2.0
// sim::FieldDutyProcess: a field's spray demand has the statistics it promises.
#include "sim/field/field_duty_process.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <vector>

namespace weedspray::sim {
namespace {

// Shares every `step_s` over `duration_s`, no headlands (one row per step).
std::vector<std::vector<double>> record(FieldDutyOptions options, std::size_t nozzles,
                                        double duration_s, double step_s, std::uint64_t seed = 7) {
  FieldDutyProcess process(nozzles, seed, options);
  std::vector<std::vector<double>> rows;
  for (double t = 0; t < duration_s; t += step_s) {
    rows.emplace_back(nozzles);
    process.shares_at(t, rows.back());
  }
  return rows;
}

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const double n = static_cast<double>(a.size());
  const double ma = std::accumulate(a.begin(), a.end(), 0.0) / n;
  const double mb = std::accumulate(b.begin(), b.end(), 0.0) / n;
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

FieldDutyOptions without_headlands() {
  FieldDutyOptions o;
  o.headland_every_s = 0;
  return o;
}

TEST(FieldDutyProcess, ANozzlesDemandIsCorrelatedOverItsCorrelationTime) {
  const auto rows = record(without_headlands(), 1, 20000.0, 1.0);
  std::vector<double> now, later, much_later;
  for (std::size_t i = 0; i + 40 < rows.size(); ++i) {
    now.push_back(rows[i][0]);
    later.push_back(rows[i + 2][0]);
    much_later.push_back(rows[i + 40][0]);
  }
  // Unlike an i.i.d. redraw each second (correlation 0), 2 s later the demand is much the same,
  // 40 s (4 correlation times) later it is nearly unrelated.
  EXPECT_GT(correlation(now, later), 0.7);
  EXPECT_LT(std::abs(correlation(now, much_later)), 0.15);
}

TEST(FieldDutyProcess, PatchesAreSharedAcrossTheBoom) {
  FieldDutyOptions shared = without_headlands();
  const auto rows = record(shared, 2, 20000.0, 1.0);
  std::vector<double> left, right;
  for (const auto& r : rows) {
    left.push_back(r[0]);
    right.push_back(r[1]);
  }
  EXPECT_GT(correlation(left, right), 0.3);
  FieldDutyOptions independent = shared;
  independent.common_share = 0;
  const auto apart = record(independent, 2, 20000.0, 1.0);
  left.clear();
  right.clear();
  for (const auto& r : apart) {
    left.push_back(r[0]);
    right.push_back(r[1]);
  }
  EXPECT_LT(std::abs(correlation(left, right)), 0.1);
}

TEST(FieldDutyProcess, NozzlesCloseWhereThereIsLittleToSprayAndOpenWithinTheirRange) {
  const FieldDutyOptions o = without_headlands();
  const auto rows = record(o, 4, 5000.0, 1.0);
  std::size_t closed = 0, all = 0;
  for (const auto& r : rows) {
    for (const double share : r) {
      ++all;
      if (share == 0.0) {
        ++closed;
      } else {
        EXPECT_GE(share, o.min_share);
        EXPECT_LE(share, o.max_share);
      }
    }
  }
  const double closed_fraction = static_cast<double>(closed) / static_cast<double>(all);
  EXPECT_GT(closed_fraction, 0.1);
  EXPECT_LT(closed_fraction, 0.5);
}

TEST(FieldDutyProcess, EveryNozzleIsOffOnTheHeadlandAndTheSpeedSwings) {
  FieldDutyOptions o;  // a 15 s headland every 2 min, +-20 % speed over 6 min
  FieldDutyProcess process(3, 11, o);
  std::vector<double> shares(3);
  double slowest = 10, fastest = 0;
  for (double t = 0; t < 720.0; t += 0.5) {
    process.shares_at(t, shares);
    const bool headland = std::fmod(t, 120.0) >= 105.0;
    EXPECT_EQ(process.headland_at(t), headland) << t;
    if (headland) {
      for (const double share : shares) EXPECT_EQ(share, 0.0) << t;
    }
    slowest = std::min(slowest, process.speed_factor_at(t));
    fastest = std::max(fastest, process.speed_factor_at(t));
  }
  EXPECT_NEAR(slowest, 0.8, 0.01);
  EXPECT_NEAR(fastest, 1.2, 0.01);
}

TEST(FieldDutyProcess, TheSameSeedGivesTheSameField) {
  const auto a = record(FieldDutyOptions{}, 3, 300.0, 0.5, 99);
  const auto b = record(FieldDutyOptions{}, 3, 300.0, 0.5, 99);
  const auto c = record(FieldDutyOptions{}, 3, 300.0, 0.5, 100);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

}  // namespace
}  // namespace weedspray::sim
