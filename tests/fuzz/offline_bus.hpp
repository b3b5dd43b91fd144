// SPDX-License-Identifier: Apache-2.0
// A D-Bus connection with no peer (one end of a socketpair), enough for sd-bus to build and
// seal method-call messages that handle_method_call() then reads: the unit tests and the
// D-Bus fuzz target call the daemon's method dispatch without a bus daemon.
#pragma once

#include <sys/socket.h>
#include <systemd/sd-bus.h>
#include <unistd.h>

#include <cstdint>
#include <stdexcept>

namespace weedspray::testing {

class OfflineBus {
 public:
  OfflineBus() {
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) < 0 || sd_bus_new(&bus_) < 0 ||
        sd_bus_set_fd(bus_, fds[0], fds[0]) < 0 || sd_bus_start(bus_) < 0)
      throw std::runtime_error("offline sd-bus connection");
    peer_ = fds[1];
  }
  ~OfflineBus() {
    // No flush: nobody reads the peer end, so a flush would wait for sd-bus's timeout.
    sd_bus_close_unref(bus_);
    ::close(peer_);
  }
  OfflineBus(const OfflineBus&) = delete;
  OfflineBus& operator=(const OfflineBus&) = delete;

  // A call of `member` on the sprayer's object; append the arguments, then seal() it.
  sd_bus_message* call(const char* member) {
    sd_bus_message* m = nullptr;
    if (sd_bus_message_new_method_call(bus_, &m, "org.weedspray.Sprayer1",
                                       "/org/weedspray/Sprayer1", "org.weedspray.Sprayer1",
                                       member) < 0)
      throw std::runtime_error("new method call");
    return m;
  }
  // Seals `m` as a received message would be and rewinds it for reading.
  static int seal(sd_bus_message* m) {
    static std::uint64_t cookie = 0;
    const int r = sd_bus_message_seal(m, ++cookie, 0);
    return r < 0 ? r : sd_bus_message_rewind(m, 1);
  }

 private:
  sd_bus* bus_ = nullptr;
  int peer_ = -1;
};

}  // namespace weedspray::testing
