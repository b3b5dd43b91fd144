// SPDX-License-Identifier: Apache-2.0
// The names --sim-fault and InjectSimFault take that carry a number (percent or count): one
// parser for all of them, 1-2 digits within each one's range, anything else refused.
#include <gtest/gtest.h>

#include "daemon/backends/sim_faults.hpp"
#include "sim/plant/hydraulic_plant.hpp"

namespace weedspray::daemon {
namespace {

TEST(SimFaults, NumberedNamesParseInRangeAndNothingElse) {
  for (const char* ok :
       {"nozzle2_blocked_30@0", "nozzle0_blocked_99@1.5", "meter_drift_10@0",
        "meter_drift_minus_30@0", "nozzles_worn_50@0", "return_valve_write_fail_2@3"}) {
    EXPECT_TRUE(parse_sim_fault(ok)) << ok;
  }
  for (const char* bad :
       {"nozzle2_blocked_0@0", "nozzle2_blocked_100@0", "nozzle2_blocked_3x@0", "meter_drift_31@0",
        "meter_drift_@0", "meter_drift_minus_0@0", "nozzles_worn_51@0",
        "return_valve_write_fail_0@0", "return_valve_write_fail_100@0", "meter_drift_-5@0"}) {
    EXPECT_FALSE(parse_sim_fault(bad)) << bad;
  }
  EXPECT_EQ(parse_sim_fault("return_valve_write_fail_12@3")->output_write_count, 12);
}

TEST(SimFaults, MeterDriftAndWearChangeThePlant) {
  sim::plant::PlantParams params;
  sim::plant::HydraulicPlant plant(params, 1);
  const double k = plant.true_meter_pulses_per_l();
  parse_sim_fault("meter_drift_10@0")->apply(plant);
  EXPECT_NEAR(plant.true_meter_pulses_per_l() / k, 1.10, 1e-9);
  parse_sim_fault("meter_drift_minus_5@0")->apply(plant);
  EXPECT_NEAR(plant.true_meter_pulses_per_l() / k, 0.95, 1e-9);
  // Every tip worn 20 %: each nozzle sprays more than the same machine unworn (the line's
  // pressure drops a little with the extra flow, so less than 20 % more).
  sim::plant::HydraulicPlant unworn(params, 1);
  sim::plant::HydraulicPlant worn(params, 1);
  parse_sim_fault("nozzles_worn_20@0")->apply(worn);
  for (auto* p : {&unworn, &worn}) {
    p->set_pump(true);
    p->set_return_valve_volts(5.0);
    p->set_valves((1u << p->nozzle_count()) - 1);
    p->step(5.0);
  }
  for (int i = 0; i < worn.nozzle_count(); ++i)
    EXPECT_GT(worn.nozzle_delivered_l(i), 1.05 * unworn.nozzle_delivered_l(i)) << i;
}

}  // namespace
}  // namespace weedspray::daemon
