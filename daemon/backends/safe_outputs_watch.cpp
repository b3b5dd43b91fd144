#include "daemon/backends/safe_outputs_watch.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "daemon/backends/backends.hpp"

namespace weedspray::daemon {

namespace {

// How long the dying daemon's line requests may take to be released.
constexpr auto kRetryFor = std::chrono::seconds(2);
constexpr auto kRetryEvery = std::chrono::milliseconds(2);

}  // namespace

int watch_and_write_safe_outputs(int fd, const std::filesystem::path& config_path,
                                 const char* program) {
  for (int signal : {SIGTERM, SIGINT, SIGHUP}) std::signal(signal, SIG_IGN);
  Config config;
  try {
    config = load_config_without_vision(config_path);
  } catch (const ConfigError& error) {
    std::fprintf(stderr, "%s: %s (not watching)\n", program, error.what());
    return 1;
  }
  char buffer[64];
  for (;;) {
    const ssize_t n = read(fd, buffer, sizeof buffer);
    if (n == 0) break;  // the daemon's process has ended
    if (n < 0 && errno != EINTR) {
      std::fprintf(stderr, "%s: reading the watch pipe (fd %d): %s; writing the outputs now\n",
                   program, fd, std::strerror(errno));
      break;
    }
  }
  const auto ended = std::chrono::steady_clock::now();
  std::vector<std::string> errors;
  int attempts = 0;
  for (;;) {
    errors.clear();
    ++attempts;
    write_hw_safe_outputs(config, errors);
    // Only a line still held (the kernel releasing the daemon's requests) is worth a retry; a
    // missing chip or device stays missing.
    const bool busy = std::any_of(errors.begin(), errors.end(), [](const std::string& e) {
      return e.find(std::strerror(EBUSY)) != std::string::npos;
    });
    if (!busy || std::chrono::steady_clock::now() - ended > kRetryFor) break;
    std::this_thread::sleep_for(kRetryEvery);
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - ended).count();
  for (const auto& error : errors) std::fprintf(stderr, "%s: %s\n", program, error.c_str());
  if (errors.empty())
    std::printf("%s: weedsprayd ended: outputs written safe %.1f ms later (%d attempt%s)\n",
                program, ms, attempts, attempts == 1 ? "" : "s");
  std::fflush(stdout);
  return errors.empty() ? 0 : 1;
}

}  // namespace weedspray::daemon
