// SPDX-License-Identifier: Apache-2.0
// The cab's view of the machine, folded from the broker's messages.
#include <gtest/gtest.h>

#include "cab/machine_view.hpp"

namespace weedspray::cab {
namespace {

TEST(CabMachineView, FoldsEachBoardsTopics) {
  MachineView view("m1");
  view.apply("weedspray/m1/left/state", R"({"state":"Spraying","t":1})");
  view.apply("weedspray/m1/left/online", "true");
  view.apply("weedspray/m1/right/online", "false");
  view.apply("weedspray/m1/left/state", R"({"state":"Idle","t":2})");  // the latest wins
  const auto json = view.to_json();
  EXPECT_EQ(json["machine"], "m1");
  EXPECT_EQ(json["boards"]["left"]["state"]["state"], "Idle");
  EXPECT_EQ(json["boards"]["left"]["online"], true);
  EXPECT_EQ(json["boards"]["right"]["online"], false);
}

TEST(CabMachineView, IgnoresOtherMachinesCommandsAndGarbage) {
  MachineView view("m1");
  view.apply("weedspray/m2/left/state", R"({"state":"Spraying"})");
  view.apply("weedspray/m1/cmd", R"({"command":"start"})");
  view.apply("weedspray/m1/left/cmd", R"({"command":"start"})");
  view.apply("weedspray/m1/left/reply", R"({"ok":true})");
  view.apply("weedspray/m1/left/state", "not json");
  EXPECT_TRUE(view.to_json()["boards"].empty());
}

TEST(CabMachineView, SaysWhetherTheBrokerIsConnected) {
  MachineView view("m1");
  EXPECT_EQ(view.to_json()["broker_connected"], false);
  view.set_broker_connected(true);
  EXPECT_EQ(view.to_json()["broker_connected"], true);
}

}  // namespace
}  // namespace weedspray::cab
