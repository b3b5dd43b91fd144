// SPDX-License-Identifier: Apache-2.0
#include "cab/picture_store.hpp"

namespace weedspray::cab {

PictureStore::PictureStore(const std::string& machine) : prefix_("weedspray/" + machine + "/") {}

bool PictureStore::apply(std::string_view topic, std::string_view payload) {
  constexpr std::string_view kLeaf = "/picture";
  if (topic.size() <= prefix_.size() + kLeaf.size() || topic.substr(0, prefix_.size()) != prefix_ ||
      topic.substr(topic.size() - kLeaf.size()) != kLeaf) {
    return false;
  }
  topic.remove_prefix(prefix_.size());
  topic.remove_suffix(kLeaf.size());
  if (topic.find('/') != std::string_view::npos) return false;
  std::lock_guard lock(mutex_);
  if (payload.empty()) {
    if (const auto it = pictures_.find(topic); it != pictures_.end()) pictures_.erase(it);
    return true;
  }
  auto& picture = pictures_[std::string(topic)];
  picture.png.assign(payload);
  picture.seq = ++seq_;
  return true;
}

std::optional<std::string> PictureStore::png(const std::string& board) const {
  std::lock_guard lock(mutex_);
  const auto it = pictures_.find(board);
  if (it == pictures_.end()) return std::nullopt;
  return it->second.png;
}

nlohmann::json PictureStore::to_json() const {
  std::lock_guard lock(mutex_);
  auto out = nlohmann::json::object();
  for (const auto& [board, picture] : pictures_) {
    out[board] = {{"seq", picture.seq}, {"bytes", picture.png.size()}};
  }
  return out;
}

}  // namespace weedspray::cab
