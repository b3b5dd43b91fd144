#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs guest test programs inside a QEMU x86-64 (or arm64) guest booted with Debian's own
# kernel, which gets the kernel's gpio-sim, Counter subsystem and interrupt-cnt (built out of
# tree here: Debian does not ship them), a test-only fixture binding interrupt-cnt to a gpio-sim
# line, and vivid.
#
#   run-vm-tests.sh [--arch amd64|arm64] [--cache DIR] [--log FILE] [--timeout SECONDS]
#                   GUEST_PROGRAM...
#
# --arch arm64: qemu-system-aarch64 -M virt -cpu cortex-a72 with Debian's arm64 kernel, the
# modules cross-built with aarch64-linux-gnu-gcc, Debian's arm64 busybox-static, gpiod and
# v4l-utils, and the programs' libraries from the arm64 sysroot (WEEDSPRAY_ARM64_SYSROOT,
# default /opt/weedspray-sysroot-arm64, made by cmake/toolchains/arm64-sysroot.sh). The
# programs must then be aarch64 builds (the arm64 preset's). The cache then also holds a
# private arm64 package index (see vm-kernel.sh).
#
# Each GUEST_PROGRAM (an executable, e.g. a gtest binary or a busybox sh script) is run in the
# guest after the simulated GPIO chips and the virtual camera are set up (see guest-init.sh).
# Exits 0 only when every program ran and exited 0; any missing prerequisite, download,
# build or boot problem is an error, never a skip.
#
# The kernel, headers and sources come from the Debian archive (`apt-get download`), chosen at
# run time from what linux-image-amd64 (-arm64) depends on, and are cached in DIR (default
# $WEEDSPRAY_BUILD_DIR/vm-cache, or $WEEDSPRAY_VM_CACHE) so later runs only pack and boot.
# --log keeps the guest's console; WEEDSPRAY_VM_KEEP_WORK=1 keeps the initramfs work dir.
set -Eeuo pipefail

script_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cache_dir="${WEEDSPRAY_VM_CACHE:-${WEEDSPRAY_BUILD_DIR:-$PWD}/vm-cache}"
log_file=""
vm_arch=amd64
boot_timeout_s=420
guest_programs=()

die() {
  echo "run-vm-tests: error: $*" >&2
  exit 2
}
note() { echo "run-vm-tests: $*" >&2; }
trap 'echo "run-vm-tests: error: command failed at line $LINENO: $BASH_COMMAND" >&2' ERR

while (($#)); do
  case "$1" in
    --arch) vm_arch="${2:?--arch needs amd64 or arm64}"; shift 2 ;;
    --cache) cache_dir="${2:?--cache needs a directory}"; shift 2 ;;
    --log) log_file="${2:?--log needs a file}"; shift 2 ;;
    --timeout) boot_timeout_s="${2:?--timeout needs seconds}"; shift 2 ;;
    -h | --help) sed -n '2,25p' "$0"; exit 0 ;;
    -*) die "unknown option '$1' (see --help)" ;;
    *) guest_programs+=("$1"); shift ;;
  esac
done
((${#guest_programs[@]})) || die "no guest program given (see --help)"
# ELF e_machine (2 bytes at offset 18) of each guest architecture: x86-64 62, aarch64 183.
case "$vm_arch" in amd64) guest_machine=62 ;; arm64) guest_machine=183 ;; *) guest_machine="" ;; esac
for program in "${guest_programs[@]}"; do
  [ -x "$program" ] || die "guest program '$program' does not exist or is not executable"
  [ "$(head -c4 "$program" | od -An -c | tr -d ' ')" = '177ELF' ] || continue # a script
  machine="$(od -An -t u2 -j 18 -N 2 "$program" | tr -d ' ')"
  [ "$machine" = "$guest_machine" ] ||
    die "guest program '$program' is ELF machine $machine, not the $vm_arch guest's ($guest_machine)"
done
mkdir -p "$cache_dir" || die "cannot create the cache directory '$cache_dir'"
cache_dir="$(cd "$cache_dir" && pwd)" # absolute: make -C changes directory

# --- prerequisites -----------------------------------------------------------------------
require_tool() { # TOOL DEBIAN_PACKAGE
  command -v "$1" >/dev/null 2>&1 ||
    die "'$1' not found: install the Debian package '$2' (./dev deps installs it)"
}
case "$vm_arch" in
  amd64) require_tool qemu-system-x86_64 qemu-system-x86 ;;
  arm64)
    require_tool qemu-system-aarch64 qemu-system-arm
    require_tool qemu-aarch64-static qemu-user-static # lists the programs' libraries
    sysroot="${WEEDSPRAY_ARM64_SYSROOT:-/opt/weedspray-sysroot-arm64}"
    [ -e "$sysroot/lib/ld-linux-aarch64.so.1" ] ||
      die "no arm64 sysroot at $sysroot: run ./dev deps (cmake/toolchains/arm64-sysroot.sh)"
    ;;
  *) die "unknown --arch '$vm_arch' (amd64 or arm64)" ;;
esac
require_tool apt-get apt
require_tool apt-cache apt
require_tool dpkg-deb dpkg
require_tool cpio cpio
require_tool xz xz-utils
require_tool modprobe kmod
require_tool depmod kmod
require_tool make make
require_tool gcc gcc
require_tool ldd libc-bin
guest_tools=(gpiodetect gpioinfo gpioget gpioset gpiomon v4l2-ctl)
if [ "$vm_arch" = amd64 ]; then # arm64: downloaded by vm_arm64_guest_tools (vm-kernel.sh)
  for tool in "${guest_tools[@]:0:5}"; do require_tool "$tool" gpiod; done
  require_tool v4l2-ctl v4l-utils
  [ -x /bin/busybox ] || die "/bin/busybox not found: install the Debian package 'busybox-static'"
  if ldd /bin/busybox >/dev/null 2>&1; then
    die "/bin/busybox is dynamically linked: install 'busybox-static' (not 'busybox')"
  fi
fi

# --- kernel and modules (shared with tests/vm-systemd) -----------------------------------
# shellcheck source=tests/vm/vm-kernel.sh
source "$script_dir/vm-kernel.sh"
vm_kernel_init
guest_modules=(configfs gpio-sim vivid interrupt-cnt) # counter comes in as a dependency
[ "$vm_arch" = amd64 ] && guest_modules+=(v4l2loopback)

# --- initramfs ----------------------------------------------------------------------------
# Two archives the kernel unpacks one after the other: a large base (busybox, modules, tools,
# every shared library; reused while none of them changes) and a small one per run (/init and
# the programs under test).
shared_libraries() { # FILE...: the absolute paths of every library they load, once each
  [ "$vm_arch" = amd64 ] || {
    shared_libraries_arm64 "$@"
    return
  }
  local file
  for file in "$@"; do
    ldd "$file" >/dev/null 2>&1 || continue # static executable or script
    if ldd "$file" | grep -q 'not found'; then
      ldd "$file" >&2
      die "'$file' needs a shared library that is not installed"
    fi
    ldd "$file" | awk '/=> \// { print $3 } /^\t\// { print $1 }'
  done | sort -u
}

# arm64: the same list from the sysroot's own loader under qemu-user (ldd cannot run an aarch64
# loader); paths are the guest's (/lib/aarch64-linux-gnu/libc.so.6), found under $sysroot.
shared_libraries_arm64() {
  local file list
  for file in "$@"; do
    [ "$(head -c4 "$file" | od -An -c | tr -d ' ')" = '177ELF' ] || continue # a script
    list="$(qemu-aarch64-static -L "$sysroot" "$sysroot/lib/ld-linux-aarch64.so.1" --list "$file")" ||
      die "the arm64 loader cannot list the libraries of '$file'"
    [ -n "$list" ] || continue # static
    if echo "$list" | grep -q 'not found'; then
      echo "$list" >&2
      die "'$file' needs a shared library that is not in the arm64 sysroot $sysroot"
    fi
    # The loader's own line reads "/lib/ld-linux-aarch64.so.1 => $sysroot/lib/...".
    echo "$list" | awk '/^\t\// { print $1; next } /=> \// { print $3 }'
  done | sort -u
}

write_cpio() { # DIR ARCHIVE
  # Uncompressed: with OpenCV's libraries (~190 MB) gzip costs ~7 s here and the emulated
  # guest unpacks a plain archive faster than it inflates a compressed one.
  (cd "$1" && find . -print0 | cpio --null -o -H newc --quiet) >"$2.tmp"
  mv "$2.tmp" "$2"
}

build_base_archive() { # -> $base_archive
  local tool_paths=() tool libraries lib key busybox=/bin/busybox lib_root=""
  if [ "$vm_arch" = arm64 ]; then
    busybox="$arm64_tools/root/bin/busybox"
    lib_root="$sysroot" # the libraries' guest paths lie below it
    for tool in "${guest_tools[@]}"; do tool_paths+=("$arm64_tools/root/usr/bin/$tool"); done
  else
    for tool in "${guest_tools[@]}"; do tool_paths+=("$(command -v "$tool")"); done
  fi
  mapfile -t libraries < <(shared_libraries "${tool_paths[@]}" "${guest_programs[@]}")
  key="$( (
    echo "$vm_arch $kernel_release $kernel_version $module_set_key" # the archive holds the modules
    # shellcheck disable=SC2016 # the format is stat's
    stat -L -c '%n %s %Y' "$busybox" "${tool_paths[@]}"
    for lib in "${libraries[@]}"; do stat -L -c '%n %s %Y' "$lib_root$lib"; done
  ) | sha256sum | cut -c1-16)"
  base_archive="$cache_dir/base-$vm_arch-$key.cpio"
  [ -f "$base_archive" ] && return 0
  find "$cache_dir" -maxdepth 1 \( -name "base-$vm_arch-*.cpio" -o -name 'base-????????????????.cpio' \) \
    -delete # this architecture's older archives, and those named before --arch existed
  local root="$work_dir/base"
  mkdir -p "$root"/{bin,usr/bin,dev,proc,sys,tmp,run}
  cp "$busybox" "$root/bin/busybox"
  cp -a "$module_root/." "$root/"
  # Debian's gpiod tools and v4l2-ctl: for the smoke test and diagnosis inside the guest.
  for tool in "${tool_paths[@]}"; do cp -L "$tool" "$root/usr/bin/"; done
  for lib in "${libraries[@]}"; do
    mkdir -p "$root$(dirname "$lib")"
    cp -L "$lib_root$lib" "$root$lib"
  done
  write_cpio "$root" "$base_archive"
  rm -rf "$root"
}

build_initramfs() { # -> $work_dir/initrd.cpio
  build_base_archive
  local root="$work_dir/run" i=0
  mkdir -p "$root/tests"
  cp "$script_dir/guest-init.sh" "$root/init"
  chmod 755 "$root/init"
  cp "$script_dir/gpio-sim-chip.sh" "$root/gpio-sim-chip.sh"
  vm_module_load_list "${guest_modules[@]}" >"$root/modules.load"
  for program in "${guest_programs[@]}"; do
    i=$((i + 1))
    cp -L "$program" "$root/tests/$(printf '%02d' "$i")-$(basename "$program")"
  done
  write_cpio "$root" "$work_dir/run.cpio"
  cat "$base_archive" "$work_dir/run.cpio" >"$work_dir/initrd.cpio"
}

# --- boot and judge -----------------------------------------------------------------------
# shellcheck disable=SC2317 # run through vm_boot
run_guest() { # -> $guest_log, vm_reached_init; returns QEMU's status
  local status=0 machine
  # amd64, isa-debug-exit: the guest writes its result to port 0xf4 and QEMU exits at once.
  # arm64 virt has no such port: the guest powers off through PSCI (QEMU exits 0); the
  # markers are the verdict either way. Its PL011 UART is ttyAMA0, and its PL061 GPIO
  # controller is a gpiochip of its own beside the gpio-sim ones.
  # arm64: each guest program may take 300 s instead of 180 s (guest-init.sh):
  # the io suite (~45 s here) made the whole test take 187 s once, with another emulator and
  # builds beside it on the 2 host cores.
  if [ "$vm_arch" = arm64 ]; then
    machine=(qemu-system-aarch64 -M virt -cpu cortex-a72 -append
      "console=ttyAMA0 quiet loglevel=3 panic=-1 oops=panic weedspray.program_timeout_s=300")
  else
    # shellcheck disable=SC2054 # the commas are QEMU's option syntax
    machine=(qemu-system-x86_64 -cpu qemu64 -device isa-debug-exit,iobase=0xf4,iosize=0x04
      -append "console=ttyS0 quiet loglevel=3 panic=-1 oops=panic")
  fi
  timeout --foreground "$boot_timeout_s" "${machine[@]}" -accel tcg -smp 2 -m 1024 \
    -nographic -no-reboot -nodefaults -serial stdio \
    -kernel "$vmlinux" -initrd "$work_dir/initrd.cpio" \
    </dev/null >"$guest_log" 2>&1 &
  vm_qemu_pid=$!
  vm_guest_log="$guest_log"
  vm_watch_boot
  wait "$vm_qemu_pid" || status=$?
  return "$status"
}

exec 9>"$cache_dir/.lock"
flock 9 # two builds sharing a cache must not prepare the kernel at once
prepare_kernel
[ "$vm_arch" = amd64 ] || vm_arm64_guest_tools
work_dir="$(mktemp -d "$cache_dir/run.XXXXXX")"
[ -n "${WEEDSPRAY_VM_KEEP_WORK:-}" ] || trap 'rm -rf "$work_dir"' EXIT # keep: for debugging
guest_log="${log_file:-$work_dir/guest.log}"
build_initramfs
note "booting $kernel_release with $(du -h "$work_dir/initrd.cpio" | cut -f1) initramfs"
boot_started=$SECONDS
qemu_status=0
vm_boot run_guest || qemu_status=$?
note "guest ran for $((SECONDS - boot_started)) s (QEMU status $qemu_status)"
sed -i 's/\r$//' "$guest_log" # the serial console ends lines with CR LF

# The markers (see guest-init.sh) are the verdict; QEMU's status only tells how it ended.
failures=()
i=0
for program in "${guest_programs[@]}"; do
  i=$((i + 1))
  name="$(basename "$program")"
  if grep -qaxF "WEEDSPRAY-VM-RESULT $(printf '%02d' "$i")-$name PASS" "$guest_log"; then
    note "PASS $name"
  else
    failures+=("$name")
  fi
done
setup_ok=1
grep -qaE '^WEEDSPRAY-VM-SETUP OK$' "$guest_log" || setup_ok=0
done_ok=1
grep -qaE '^WEEDSPRAY-VM-DONE$' "$guest_log" || done_ok=0

# Measured figures (e.g. the pulse rate reached): shown however the run ends.
grep -a '^WEEDSPRAY-VM-FIGURE ' "$guest_log" | sed 's/^WEEDSPRAY-VM-FIGURE /run-vm-tests: figure: /' >&2 || true

if ((${#failures[@]} == 0 && setup_ok && done_ok)); then
  note "all ${#guest_programs[@]} guest programs passed"
  exit 0
fi
echo "===== guest console =====" >&2
cat -v "$guest_log" >&2
echo "===== end of guest console =====" >&2
((vm_reached_init)) || note "FAIL: the guest kernel did not start /init in either boot"
((setup_ok)) || note "FAIL: guest setup did not complete (no WEEDSPRAY-VM-SETUP OK)"
((done_ok)) || note "FAIL: guest did not finish (no WEEDSPRAY-VM-DONE; QEMU status $qemu_status, 124 = timeout after $boot_timeout_s s)"
for name in "${failures[@]}"; do note "FAIL $name"; done
exit 1
