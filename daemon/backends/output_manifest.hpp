// SPDX-License-Identifier: Apache-2.0
// The output manifest: weedsprayd's resolved configuration (drop-ins merged, defaults filled in),
// written under /run when it starts in hardware mode. The safe writers that run without the
// daemon (its exit watcher, the unit's ExecStopPost) read it instead of the editable files, so a
// configuration broken after the start (a typo being edited) cannot stop them writing the
// outputs the daemon actually drove.
#pragma once

#include <filesystem>
#include <optional>

#include "daemon/config/config.hpp"

namespace weedspray::daemon {

// Writes `config` to `path` whole or not at all (a temporary file, fsync, rename). Throws
// std::runtime_error naming the path.
void write_output_manifest(const Config& config, const std::filesystem::path& path);

// The configuration the safe writers use: the manifest when it exists and loads, else
// `config_path` (each fallback said on stderr, prefixed by `program`). nullopt when neither
// loads (the errors said).
std::optional<Config> load_safe_outputs_config(const std::filesystem::path& config_path,
                                               const std::filesystem::path& manifest_path,
                                               const char* program);

}  // namespace weedspray::daemon
