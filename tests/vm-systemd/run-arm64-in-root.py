#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Runs an arm64 program inside an arm64 root directory on an x86-64 host, without binfmt_misc.

    run-arm64-in-root.py ROOT PROGRAM [ARG...]

The arm64 systemd guest's rootfs is provisioned on the host this way (debootstrap's second
stage, dpkg -i of the package), which takes minutes instead of the 11+ min the same work took
inside the TCG-emulated guest. proot (ptrace) maps every path into ROOT and runs each aarch64
program it execs, children included, under qemu-aarch64-static (-q): no binfmt_misc, which CI
machines lack.

Debian 12's proot (5.1.0) does not know two newer syscalls: statx and faccessat2. The emulated
glibc and coreutils use them, and proot passes them through untranslated, so they look at the
host's paths (`[ -x /debootstrap/debootstrap ]` fails, `ls -l` shows the host's /etc). A seccomp
filter answers both with ENOSYS; qemu-user and glibc then fall back to newfstatat/faccessat,
which proot translates. The filter's default action stays ALLOW, for foreign architectures too:
proot cancels a syscall by setting an invalid number, which libseccomp's default "bad
architecture" action (kill) would take for an x32 call.

mount(2) is refused (EPERM). We are root, so a mount would really happen, on the host's path
(debootstrap's second stage mounts proc and sys and tolerates the refusal). And with /proc
there, the systemd postinst's systemd-tmpfiles calls readlinkat(fd, "") on an O_PATH fd, which
aborts proot 5.1 (assertion in compare_paths2); without /proc it skips its work, as it does in
the x86 guest's chroot, and the guest's boot runs it.
"""
import errno
import os
import sys

import seccomp  # Debian: python3-seccomp


def main() -> None:
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    root, command = sys.argv[1], sys.argv[2:]
    syscall_filter = seccomp.SyscallFilter(seccomp.ALLOW)
    syscall_filter.set_attr(seccomp.Attr.ACT_BADARCH, seccomp.ALLOW)
    for name in ("statx", "faccessat2"):
        syscall_filter.add_rule(seccomp.ERRNO(errno.ENOSYS), name)
    syscall_filter.add_rule(seccomp.ERRNO(errno.EPERM), "mount")
    syscall_filter.load()
    os.execvp("proot", ["proot", "-q", "qemu-aarch64-static", "-w", "/", "-r", root] + command)


if __name__ == "__main__":
    main()
