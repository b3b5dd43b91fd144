// SPDX-License-Identifier: Apache-2.0
// The weed model a configuration names: found (model_search_dirs), read with the description
// beside it (NAME.json), and its spec merged with the vision.model_* keys, each override checked
// against what the description says. Once, when the configuration is loaded.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "vision/weed_source.hpp"

namespace weedspray::daemon {

// The spec the vision.model_* keys give by themselves (no model read).
[[nodiscard]] vision::DnnModelSpec dnn_spec(const VisionSection& vision);

// The model_* keys' own rules, each reported against the key that breaks it. Throws
// VisionKeyError.
void check_model_spec(const Config& config);

// Finds and reads vision.model and its description; the spec is the description's with the
// configuration's overrides applied. Throws VisionKeyError naming vision.model or the key.
[[nodiscard]] std::shared_ptr<LoadedModel> read_model(const Config& config);

// A number as the messages about a model's spec write it (e.g. 0.94, 1e-05).
[[nodiscard]] std::string spec_number_text(double value);

// Folders a relative vision.model is looked up in, in order: the folder of the file that set
// it (when it was set in a file), the installed models, and a build tree's models/.
[[nodiscard]] std::vector<std::filesystem::path> model_search_dirs(const std::string& set_in_file);

}  // namespace weedspray::daemon
