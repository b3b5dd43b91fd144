// SPDX-License-Identifier: Apache-2.0
// The loader's two halves: reading and validating the files (weedspray_config, no vision
// library) and the weed source check that reads the model and builds the vision pipelines
// (vision_config.cpp, passed in as a function). load_config() joins them; the fail-safe writer
// (weedspray-safe-outputs) loads without the check, so it starts fast with few libraries.
#pragma once

#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "daemon/config/config.hpp"

namespace weedspray::daemon {

// A problem with one [vision] key ("vision.model", ...), raised while checking the weed
// source; the loader turns it into a ConfigError naming where the key was set.
class VisionKeyError : public std::runtime_error {
 public:
  VisionKeyError(std::string key, const std::string& message)
      : std::runtime_error(message), key_(std::move(key)) {}
  const std::string& key() const { return key_; }

 private:
  std::string key_;
};

// Checks the weed source of a loaded configuration; returns its model (null when none).
// Throws VisionKeyError.
using WeedSourceCheck = std::shared_ptr<const LoadedModel> (*)(const Config&);

// `check` may be null: the weed source keys are then not checked and no model is read.
[[nodiscard]] Config load_config_files(const std::filesystem::path& main_file,
                                       WeedSourceCheck check);
[[nodiscard]] Config load_config_documents(
    const std::vector<std::pair<std::string, std::string>>& documents, WeedSourceCheck check);

}  // namespace weedspray::daemon
