// SPDX-License-Identifier: Apache-2.0
// Appends whole lines to a file: each line goes out in one write(2) on an O_APPEND descriptor,
// and a write that fails or lands short (ENOSPC, EIO, EFBIG) is cut back off with ftruncate,
// so the file only ever holds whole lines. Not thread-safe; one writer per file.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <string_view>

namespace weedspray::daemon {

// The write(2) used for appends: a seam for tests that simulate a full disk (short writes).
using WriteCall = ssize_t (*)(int fd, const void* data, std::size_t size);

class LineAppender {
 public:
  explicit LineAppender(WriteCall write_call = nullptr);
  ~LineAppender();
  LineAppender(const LineAppender&) = delete;
  LineAppender& operator=(const LineAppender&) = delete;

  // Creates (or appends to) `path`. Returns 0 or the errno of the failed open.
  int open(const std::filesystem::path& path);
  void close();
  bool is_open() const { return fd_ >= 0; }

  // Appends `line` (which ends in '\n') whole, or not at all. Returns 0 or an errno (ENOSPC for
  // a short write). When the cut-back itself fails the file is closed and EIO returned, so the
  // next open starts from what is on disk.
  int append(std::string_view line);
  // fdatasync: the appended lines on the card. Returns 0 or an errno.
  int sync();
  // Bytes of whole lines in the file.
  std::uintmax_t size() const { return size_; }

 private:
  WriteCall write_call_;
  int fd_ = -1;
  std::uintmax_t size_ = 0;
};

}  // namespace weedspray::daemon
