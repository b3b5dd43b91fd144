#!/usr/bin/env bash
# Runs guest test programs inside a QEMU x86-64 guest booted with Debian's own kernel, which
# gets the kernel's gpio-sim, Counter subsystem and interrupt-cnt (built out of tree here:
# Debian does not ship them), a test-only fixture binding interrupt-cnt to a gpio-sim line, and
# vivid.
#
#   run-vm-tests.sh [--cache DIR] [--log FILE] [--timeout SECONDS] GUEST_PROGRAM...
#
# Each GUEST_PROGRAM (an executable, e.g. a gtest binary or a busybox sh script) is run in the
# guest after the simulated GPIO chips and the virtual camera are set up (see guest-init.sh).
# Exits 0 only when every program ran and exited 0; any missing prerequisite, download,
# build or boot problem is an error, never a skip.
#
# The kernel, headers and sources come from the Debian archive (`apt-get download`), chosen at
# run time from what linux-image-amd64 depends on, and are cached in DIR (default
# $WEEDSPRAY_BUILD_DIR/vm-cache, or $WEEDSPRAY_VM_CACHE) so later runs only pack and boot.
# --log keeps the guest's console; WEEDSPRAY_VM_KEEP_WORK=1 keeps the initramfs work dir.
set -Eeuo pipefail

script_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cache_dir="${WEEDSPRAY_VM_CACHE:-${WEEDSPRAY_BUILD_DIR:-$PWD}/vm-cache}"
log_file=""
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
    --cache) cache_dir="${2:?--cache needs a directory}"; shift 2 ;;
    --log) log_file="${2:?--log needs a file}"; shift 2 ;;
    --timeout) boot_timeout_s="${2:?--timeout needs seconds}"; shift 2 ;;
    -h | --help) sed -n '2,17p' "$0"; exit 0 ;;
    -*) die "unknown option '$1' (see --help)" ;;
    *) guest_programs+=("$1"); shift ;;
  esac
done
((${#guest_programs[@]})) || die "no guest program given (see --help)"
for program in "${guest_programs[@]}"; do
  [ -x "$program" ] || die "guest program '$program' does not exist or is not executable"
done
mkdir -p "$cache_dir" || die "cannot create the cache directory '$cache_dir'"
cache_dir="$(cd "$cache_dir" && pwd)" # absolute: make -C changes directory

# --- prerequisites -----------------------------------------------------------------------
require_tool() { # TOOL DEBIAN_PACKAGE
  command -v "$1" >/dev/null 2>&1 ||
    die "'$1' not found: install the Debian package '$2' (./dev deps installs it)"
}
require_tool qemu-system-x86_64 qemu-system-x86
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
for tool in "${guest_tools[@]:0:5}"; do require_tool "$tool" gpiod; done
require_tool v4l2-ctl v4l-utils
[ -x /bin/busybox ] || die "/bin/busybox not found: install the Debian package 'busybox-static'"
if ldd /bin/busybox >/dev/null 2>&1; then
  die "/bin/busybox is dynamically linked: install 'busybox-static' (not 'busybox')"
fi

# --- which kernel --------------------------------------------------------------------------
# The ABI (6.1.0-NN) moves with Debian's point releases, so ask the package index.
kernel_image_package() {
  apt-cache depends linux-image-amd64 2>/dev/null |
    sed -n 's/^ *Depends: \(linux-image-[0-9][^ ]*-amd64\)$/\1/p' | head -n1 || true
}
image_package="$(kernel_image_package)"
if [ -z "$image_package" ] && [ "$(id -u)" -eq 0 ]; then
  note "linux-image-amd64 is not in the package index; running apt-get update"
  apt-get update -qq || die "apt-get update failed"
  image_package="$(kernel_image_package)"
fi
[ -n "$image_package" ] ||
  die "cannot find what linux-image-amd64 depends on in the package index (run apt-get update)"
kernel_release="${image_package#linux-image-}"
kernel_version="$(apt-cache show --no-all-versions "$image_package" 2>/dev/null |
  sed -n 's/^Version: //p' || true)"
[ -n "$kernel_version" ] || die "no version of $image_package in the package index"
abi="${kernel_release%-amd64}"                           # 6.1.0-56
series="$(echo "$kernel_release" | cut -d. -f1,2)"        # 6.1: linux-source-6.1
gcc_version="$(apt-cache depends "linux-headers-$kernel_release" 2>/dev/null |
  sed -n 's/^ *Depends: linux-compiler-gcc-\([0-9]*\)-x86$/\1/p' | head -n1 || true)"
[ -n "$gcc_version" ] || die "cannot tell which gcc linux-headers-$kernel_release is built with"
require_tool "gcc-$gcc_version" "gcc-$gcc_version"

# The modules built here, from linux-source (file lists in extract_module_sources).
built_modules=(gpio-sim counter interrupt-cnt)
# Loaded by guest-init.sh after it has made the gpio-sim chips, not from modules.load.
fixture_source="$script_dir/interrupt_counter_fixture.c"
[ -f "$fixture_source" ] || die "$fixture_source is missing"
# Bump when the module build steps change: a new value makes a new kernel_dir (and the old
# one is removed), so a cache never lacks a module the guest now expects.
module_build_revision=2
module_set_key="$( (
  echo "$module_build_revision ${built_modules[*]}"
  cat "$fixture_source"
) | sha256sum | cut -c1-12)"
kernel_dir="$cache_dir/$kernel_release-$kernel_version-modules-$module_set_key"
vmlinux="$kernel_dir/vmlinux"
module_root="$kernel_dir/modules" # lib/modules/$kernel_release with only what the guest needs
module_load_list="$kernel_dir/modules.load"
guest_modules=(configfs gpio-sim vivid interrupt-cnt) # counter comes in as a dependency

fetch_packages() { # -> $kernel_dir/debs
  local debs="$kernel_dir/debs"
  mkdir -p "$debs"
  local packages=("$image_package=$kernel_version" "linux-headers-$kernel_release=$kernel_version"
    "linux-headers-$abi-common=$kernel_version" "linux-kbuild-$series=$kernel_version"
    "linux-source-$series=$kernel_version")
  note "downloading ${packages[*]} from the Debian archive"
  (cd "$debs" && apt-get download -q "${packages[@]}") >"$kernel_dir/download.log" 2>&1 || {
    cat "$kernel_dir/download.log" >&2
    die "apt-get download failed (network? stale index: run apt-get update)"
  }
}

extract_vmlinux() { # vmlinuz -> vmlinux: booting the ELF via PVH skips emulated decompression
  local vmlinuz="$1" offset
  offset="$(LC_ALL=C grep -m1 -obUaP '\xFD7zXZ\x00' "$vmlinuz" | cut -d: -f1)"
  [ -n "$offset" ] || die "no xz payload in $vmlinuz (kernel compression changed?)"
  # xz stops reading at the end of its stream, so tail must not be part of a checked pipe.
  xz -dc --single-stream <(tail -c +$((offset + 1)) "$vmlinuz" 2>/dev/null || true) >"$vmlinux.tmp"
  [ "$(head -c4 "$vmlinux.tmp" | od -An -c | tr -d ' ')" = '177ELF' ] ||
    die "the xz payload of $vmlinuz is not an ELF vmlinux"
  mv "$vmlinux.tmp" "$vmlinux"
}

module_src="$kernel_dir/module-src"
extract_module_sources() { # -> $module_src (the whole 1.3 GB tarball is read: ~10 s)
  rm -rf "$module_src" && mkdir -p "$module_src"
  local top="linux-source-$series" counter="linux-source-$series/drivers/counter"
  # The Counter core's own headers are private; <linux/counter.h> is in the headers package.
  dpkg-deb --fsys-tarfile "$kernel_dir/debs/${top}_"*.deb |
    tar -xO "./usr/src/$top.tar.xz" | xz -dc |
    tar -x -C "$module_src" --strip-components=1 "$top/drivers/gpio/gpio-sim.c" \
      "$top/drivers/gpio/gpiolib.h" "$top/kernel/irq/irq_sim.c" \
      "$counter/counter-core.c" "$counter/counter-sysfs.c" "$counter/counter-chrdev.c" \
      "$counter/counter-sysfs.h" "$counter/counter-chrdev.h" "$counter/interrupt-cnt.c"
}

# ROOT -> ROOT/lib/modules/$kernel_release/extra/: gpio-sim.ko, counter.ko, interrupt-cnt.ko
# (the modules Debian's kernel lacks) and interrupt_counter_fixture.ko (test-only).
build_modules() {
  local root="$1" src="$module_src"
  local headers="$root/usr/src/linux-headers-$kernel_release"
  mv "$src/drivers/gpio/gpio-sim.c" "$src/gpio-sim-main.c"
  mv "$src/drivers/gpio/gpiolib.h" "$src/kernel/irq/irq_sim.c" "$src/drivers/counter/"* "$src/"
  cp "$fixture_source" "$src/"
  # irq_to_desc() is not exported to modules; generic_handle_irq() does the same lookup.
  grep -q 'handle_simple_irq(irq_to_desc(irqnum));' "$src/irq_sim.c" ||
    die "irq_sim.c no longer has the line this script patches; update build_modules"
  sed -i 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq(irqnum);/' "$src/irq_sim.c"
  # As drivers/{gpio,counter}/Makefile build them (CONFIG_GPIO_SIM, COUNTER, INTERRUPT_CNT).
  cat >"$src/Kbuild" <<'KBUILD'
obj-m := gpio-sim.o counter.o interrupt-cnt.o interrupt_counter_fixture.o
gpio-sim-y := gpio-sim-main.o irq_sim.o
counter-y := counter-core.o counter-sysfs.o counter-chrdev.o
KBUILD
  # The headers' Makefile includes the -common one by absolute /usr/src path.
  sed -i "s#^include /usr/src/#include $root/usr/src/#" "$headers/Makefile"
  note "building ${built_modules[*]} and the interrupt-cnt fixture against linux-headers-$kernel_release"
  make -C "$headers" M="$src" -j2 modules >"$kernel_dir/modules-build.log" 2>&1 || {
    cat "$kernel_dir/modules-build.log" >&2
    die "building the out-of-tree modules failed"
  }
  mkdir -p "$root/lib/modules/$kernel_release/extra"
  local module
  for module in "${built_modules[@]}" interrupt_counter_fixture; do
    cp "$src/$module.ko" "$root/lib/modules/$kernel_release/extra/"
  done
}

stage_modules() { # ROOT -> $module_root + $module_load_list (insmod order, dependencies first)
  local root="$1"
  depmod -b "$root" "$kernel_release"
  rm -rf "$module_root" && mkdir -p "$module_root"
  : >"$module_load_list.tmp"
  local line path
  while read -r line; do
    case "$line" in
      insmod\ *) ;;
      builtin\ *) continue ;;
      *) die "unexpected modprobe output: $line" ;;
    esac
    path="${line#insmod }"
    path="${path%% *}"
    path="${path#"$root"}"
    grep -qxF "$path" "$module_load_list.tmp" && continue
    mkdir -p "$module_root$(dirname "$path")"
    cp "$root$path" "$module_root$path"
    echo "$path" >>"$module_load_list.tmp"
  done < <(for m in "${guest_modules[@]}"; do
    modprobe -d "$root" -S "$kernel_release" --show-depends "$m" ||
      die "modprobe cannot resolve module '$m' for $kernel_release"
  done)
  mv "$module_load_list.tmp" "$module_load_list"
}

prepare_kernel() {
  [ -f "$kernel_dir/ready" ] && return 0
  local started=$SECONDS root="$kernel_dir/root"
  rm -rf "$kernel_dir" && mkdir -p "$kernel_dir"
  fetch_packages
  note "unpacking the kernel packages and the module sources"
  # Both are single-threaded xz streams: unpack them side by side.
  extract_module_sources &
  local sources_job=$!
  mkdir -p "$root"
  for deb in "$kernel_dir"/debs/linux-{image,headers,kbuild}-*.deb; do dpkg-deb -x "$deb" "$root"; done
  extract_vmlinux "$root/boot/vmlinuz-$kernel_release"
  wait "$sources_job" || die "extracting the module sources from linux-source-$series failed"
  build_modules "$root"
  stage_modules "$root"
  local fixture="lib/modules/$kernel_release/extra/interrupt_counter_fixture.ko"
  cp "$root/$fixture" "$module_root/$fixture"
  rm -rf "$root" "$module_src" "$kernel_dir/debs" # keep what boots, ~80 MB
  # Keep only this kernel: older ABIs are never booted again.
  find "$cache_dir" -mindepth 1 -maxdepth 1 -type d ! -path "$kernel_dir" -exec rm -rf {} +
  touch "$kernel_dir/ready"
  note "kernel $kernel_release ($kernel_version) prepared in $((SECONDS - started)) s"
}

# --- initramfs ----------------------------------------------------------------------------
# Two archives the kernel unpacks one after the other: a large base (busybox, modules, tools,
# every shared library; reused while none of them changes) and a small one per run (/init and
# the programs under test).
shared_libraries() { # FILE...: the absolute paths of every library they load, once each
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

write_cpio() { # DIR ARCHIVE
  # Uncompressed: with OpenCV's libraries (~190 MB) gzip costs ~7 s here and the emulated
  # guest unpacks a plain archive faster than it inflates a compressed one.
  (cd "$1" && find . -print0 | cpio --null -o -H newc --quiet) >"$2.tmp"
  mv "$2.tmp" "$2"
}

build_base_archive() { # -> $base_archive
  local tool_paths=() tool libraries lib key
  for tool in "${guest_tools[@]}"; do tool_paths+=("$(command -v "$tool")"); done
  mapfile -t libraries < <(shared_libraries "${tool_paths[@]}" "${guest_programs[@]}")
  key="$( (
    echo "$kernel_release $kernel_version $module_set_key" # the archive holds the modules
    # shellcheck disable=SC2016 # the format is stat's
    stat -L -c '%n %s %Y' /bin/busybox "${tool_paths[@]}" "${libraries[@]}"
  ) | sha256sum | cut -c1-16)"
  base_archive="$cache_dir/base-$key.cpio"
  [ -f "$base_archive" ] && return 0
  find "$cache_dir" -maxdepth 1 -name 'base-*.cpio' -delete
  local root="$work_dir/base"
  mkdir -p "$root"/{bin,usr/bin,dev,proc,sys,tmp,run}
  cp /bin/busybox "$root/bin/busybox"
  cp -a "$module_root/." "$root/"
  # Debian's gpiod tools and v4l2-ctl: for the smoke test and diagnosis inside the guest.
  for tool in "${tool_paths[@]}"; do cp -L "$tool" "$root/usr/bin/"; done
  for lib in "${libraries[@]}"; do
    mkdir -p "$root$(dirname "$lib")"
    cp -L "$lib" "$root$lib"
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
  cp "$module_load_list" "$root/modules.load"
  for program in "${guest_programs[@]}"; do
    i=$((i + 1))
    cp -L "$program" "$root/tests/$(printf '%02d' "$i")-$(basename "$program")"
  done
  write_cpio "$root" "$work_dir/run.cpio"
  cat "$base_archive" "$work_dir/run.cpio" >"$work_dir/initrd.cpio"
}

# --- boot and judge -----------------------------------------------------------------------
run_guest() { # -> $guest_log; returns QEMU's status
  local status=0
  # isa-debug-exit: the guest writes its result to port 0xf4 and QEMU exits at once.
  timeout --foreground "$boot_timeout_s" qemu-system-x86_64 -accel tcg -cpu qemu64 -smp 2 -m 1024 \
    -nographic -no-reboot -nodefaults -serial stdio \
    -device isa-debug-exit,iobase=0xf4,iosize=0x04 \
    -kernel "$vmlinux" -initrd "$work_dir/initrd.cpio" \
    -append "console=ttyS0 quiet loglevel=3 panic=-1 oops=panic" \
    </dev/null >"$guest_log" 2>&1 || status=$?
  return "$status"
}

exec 9>"$cache_dir/.lock"
flock 9 # two builds sharing a cache must not prepare the kernel at once
prepare_kernel
work_dir="$(mktemp -d "$cache_dir/run.XXXXXX")"
[ -n "${WEEDSPRAY_VM_KEEP_WORK:-}" ] || trap 'rm -rf "$work_dir"' EXIT # keep: for debugging
guest_log="${log_file:-$work_dir/guest.log}"
build_initramfs
note "booting $kernel_release with $(du -h "$work_dir/initrd.cpio" | cut -f1) initramfs"
boot_started=$SECONDS
qemu_status=0
run_guest || qemu_status=$?
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
((setup_ok)) || note "FAIL: guest setup did not complete (no WEEDSPRAY-VM-SETUP OK)"
((done_ok)) || note "FAIL: guest did not finish (no WEEDSPRAY-VM-DONE; QEMU status $qemu_status, 124 = timeout after $boot_timeout_s s)"
for name in "${failures[@]}"; do note "FAIL $name"; done
exit 1
