// SPDX-License-Identifier: Apache-2.0
#include "daemon/backends/output_manifest.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

namespace weedspray::daemon {

namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const char* what) {
  throw std::runtime_error("output manifest " + path.string() + ": " + what + ": " +
                           std::strerror(errno));
}

}  // namespace

void write_output_manifest(const Config& config, const std::filesystem::path& path) {
  const std::string text =
      "# weedsprayd's resolved configuration at its start (pid " + std::to_string(::getpid()) +
      "), read by weedspray-safe-outputs.\n# Written by weedsprayd: edit the files under "
      "/etc/weedspray instead.\n" +
      dump_config(config);
  const std::filesystem::path temporary = path.string() + ".new";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0640);
  if (fd < 0) fail(temporary, "cannot create");
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ::close(fd);
      fail(temporary, "cannot write");
    }
    written += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    ::close(fd);
    fail(temporary, "cannot sync");
  }
  if (::close(fd) != 0) fail(temporary, "cannot close");
  if (::rename(temporary.c_str(), path.c_str()) != 0) fail(path, "cannot rename into place");
}

std::optional<Config> load_safe_outputs_config(const std::filesystem::path& config_path,
                                               const std::filesystem::path& manifest_path,
                                               const char* program) {
  if (!manifest_path.empty()) {
    std::error_code error;
    if (std::filesystem::exists(manifest_path, error)) {
      try {
        return load_config_without_vision(manifest_path);
      } catch (const ConfigError& failure) {
        std::fprintf(stderr, "%s: %s; using %s\n", program, failure.what(), config_path.c_str());
      }
    } else {
      std::fprintf(stderr, "%s: no output manifest %s (weedsprayd did not start); using %s\n",
                   program, manifest_path.c_str(), config_path.c_str());
    }
  }
  try {
    return load_config_without_vision(config_path);
  } catch (const ConfigError& failure) {
    std::fprintf(stderr, "%s: %s\n", program, failure.what());
    return std::nullopt;
  }
}

}  // namespace weedspray::daemon
