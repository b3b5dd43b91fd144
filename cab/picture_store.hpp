// SPDX-License-Identifier: Apache-2.0
// The latest live-view picture of every board (a PNG on weedspray/<machine>/<board>/picture),
// kept for the page, each with a number that grows with every new one so the page knows when to
// fetch it again. Thread-safe: the MQTT side writes, the HTTP side reads.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace weedspray::cab {

class PictureStore {
 public:
  explicit PictureStore(const std::string& machine);

  // Keeps the payload when `topic` is a board's picture topic (an empty one forgets the board's
  // picture); returns whether it was one.
  bool apply(std::string_view topic, std::string_view payload);

  // The board's latest PNG, if one came.
  [[nodiscard]] std::optional<std::string> png(const std::string& board) const;
  // {"<board>": {"seq": N, "bytes": size}} for the boards with a picture.
  [[nodiscard]] nlohmann::json to_json() const;

 private:
  struct Picture {
    std::string png;
    std::uint64_t seq = 0;
  };
  std::string prefix_;  // "weedspray/<machine>/"
  mutable std::mutex mutex_;
  std::map<std::string, Picture, std::less<>> pictures_;
  std::uint64_t seq_ = 0;
};

}  // namespace weedspray::cab
