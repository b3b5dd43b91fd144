// SPDX-License-Identifier: Apache-2.0
#include "daemon/backends/emergency_write_handoff.hpp"

#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <type_traits>

namespace weedspray::daemon {

namespace {

// Both ends are the same build on the same machine: the struct travels as its bytes.
static_assert(std::is_trivially_copyable_v<io::EmergencyWrite>);

union ControlBuffer {
  char bytes[CMSG_SPACE(sizeof(int))];
  cmsghdr align;
};

}  // namespace

int hand_emergency_writes(int socket_fd) noexcept {
  int sent = 0;
  io::EmergencyWrite write;
  for (std::size_t i = 0; io::EmergencyOutputs::get(i, write); ++i) {
    iovec data{&write, sizeof write};
    ControlBuffer control{};
    msghdr message{};
    message.msg_iov = &data;
    message.msg_iovlen = 1;
    message.msg_control = control.bytes;
    message.msg_controllen = sizeof control.bytes;
    cmsghdr* header = CMSG_FIRSTHDR(&message);
    header->cmsg_level = SOL_SOCKET;
    header->cmsg_type = SCM_RIGHTS;
    header->cmsg_len = CMSG_LEN(sizeof(int));
    std::memcpy(CMSG_DATA(header), &write.fd, sizeof(int));
    ssize_t n;
    do {
      n = ::sendmsg(socket_fd, &message, MSG_NOSIGNAL);
    } while (n < 0 && errno == EINTR);
    if (n < 0) return -errno;
    ++sent;
  }
  return sent;
}

int receive_emergency_write(int socket_fd, io::EmergencyWrite& out) noexcept {
  io::EmergencyWrite write;
  iovec data{&write, sizeof write};
  ControlBuffer control{};
  msghdr message{};
  message.msg_iov = &data;
  message.msg_iovlen = 1;
  message.msg_control = control.bytes;
  message.msg_controllen = sizeof control.bytes;
  ssize_t n;
  do {
    n = ::recvmsg(socket_fd, &message, MSG_CMSG_CLOEXEC);
  } while (n < 0 && errno == EINTR);
  if (n < 0) return -errno;
  if (n == 0) return 0;
  int fd = -1;
  for (cmsghdr* header = CMSG_FIRSTHDR(&message); header != nullptr;
       header = CMSG_NXTHDR(&message, header)) {
    if (header->cmsg_level == SOL_SOCKET && header->cmsg_type == SCM_RIGHTS &&
        header->cmsg_len == CMSG_LEN(sizeof(int)))
      std::memcpy(&fd, CMSG_DATA(header), sizeof(int));
  }
  if (n != static_cast<ssize_t>(sizeof write) || fd < 0 || (message.msg_flags & MSG_CTRUNC)) {
    if (fd >= 0) ::close(fd);
    return -EBADMSG;
  }
  write.fd = fd;
  out = write;
  return 1;
}

}  // namespace weedspray::daemon
