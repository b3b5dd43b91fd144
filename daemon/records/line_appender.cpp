// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/line_appender.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>

namespace weedspray::daemon {

LineAppender::LineAppender(WriteCall write_call)
    : write_call_(write_call != nullptr ? write_call : &::write) {}

LineAppender::~LineAppender() {
  close();
}

namespace {

// The length of `fd`'s content up to and including its last '\n' (0: none).
std::uintmax_t whole_lines_end(int fd, std::uintmax_t size) {
  char block[4096];
  std::uintmax_t end = size;
  while (end > 0) {
    const std::size_t n = end < sizeof block ? static_cast<std::size_t>(end) : sizeof block;
    const ssize_t got = ::pread(fd, block, n, static_cast<off_t>(end - n));
    if (got != static_cast<ssize_t>(n)) return 0;
    for (std::size_t i = n; i > 0; --i) {
      if (block[i - 1] == '\n') return end - n + i;
    }
    end -= n;
  }
  return 0;
}

}  // namespace

int LineAppender::open(const std::filesystem::path& path) {
  close();
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) return errno;
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int error = errno;
    ::close(fd);
    return error;
  }
  // A torn last line (a power cut, a cut-back that failed) is cut off before appending to it.
  const auto size = static_cast<std::uintmax_t>(st.st_size);
  const std::uintmax_t whole = whole_lines_end(fd, size);
  if (whole != size && ::ftruncate(fd, static_cast<off_t>(whole)) != 0) {
    const int error = errno;
    ::close(fd);
    return error;
  }
  fd_ = fd;
  size_ = whole;
  return 0;
}

void LineAppender::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  size_ = 0;
}

int LineAppender::append(std::string_view line) {
  if (fd_ < 0) return EBADF;
  ssize_t written;
  do {
    written = write_call_(fd_, line.data(), line.size());
  } while (written < 0 && errno == EINTR);
  if (written == static_cast<ssize_t>(line.size())) {
    size_ += line.size();
    return 0;
  }
  // A short write returns no errno: the disk filled up part-way through the line.
  const int error = written < 0 ? errno : ENOSPC;
  // Part of the line may have landed (a short write, or EIO after some blocks): cut it off.
  // Freeing blocks needs no space, so this works on a full disk.
  int cut;
  do {
    cut = ::ftruncate(fd_, static_cast<off_t>(size_));
  } while (cut != 0 && errno == EINTR);
  if (cut != 0) {
    close();
    return EIO;
  }
  return error;
}

int LineAppender::sync() {
  if (fd_ < 0) return 0;
  return ::fdatasync(fd_) == 0 ? 0 : errno;
}

}  // namespace weedspray::daemon
