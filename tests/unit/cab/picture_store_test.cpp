// SPDX-License-Identifier: Apache-2.0
// The cab's latest picture of every board, kept from the broker's picture topics.
#include <gtest/gtest.h>

#include "cab/picture_store.hpp"

namespace weedspray::cab {
namespace {

TEST(CabPictureStore, KeepsEachBoardsLatestPicture) {
  PictureStore store("m1");
  EXPECT_FALSE(store.png("left"));
  EXPECT_TRUE(store.apply("weedspray/m1/left/picture", "first"));
  EXPECT_TRUE(store.apply("weedspray/m1/right/picture", "other"));
  EXPECT_TRUE(store.apply("weedspray/m1/left/picture", "second"));
  EXPECT_EQ(store.png("left"), "second");
  EXPECT_EQ(store.png("right"), "other");
  const auto json = store.to_json();
  EXPECT_EQ(json["left"]["bytes"], 6);
  EXPECT_GT(json["left"]["seq"], json["right"]["seq"]);        // a new picture, a new number
  EXPECT_TRUE(store.apply("weedspray/m1/right/picture", ""));  // a cleared retained picture
  EXPECT_FALSE(store.png("right"));
}

TEST(CabPictureStore, IgnoresOtherTopics) {
  PictureStore store("m1");
  EXPECT_FALSE(store.apply("weedspray/m2/left/picture", "png"));
  EXPECT_FALSE(store.apply("weedspray/m1/left/state", "{}"));
  EXPECT_FALSE(store.apply("weedspray/m1/picture", "png"));
  EXPECT_FALSE(store.apply("weedspray/m1/a/b/picture", "png"));
  EXPECT_TRUE(store.to_json().empty());
}

}  // namespace
}  // namespace weedspray::cab
