# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=bash
# Shared by tests/vm/run-vm-tests.sh and tests/vm-systemd/run-systemd-vm-test.sh (sourced,
# never run): Debian's own kernel for the QEMU guests, plus the modules Debian does not ship,
# built out of tree from linux-source:
#   gpio-sim (+ irq_sim), counter + interrupt-cnt, interrupt_counter_fixture (test-only),
#   industrialio-configfs + industrialio-sw-device + iio_dummy (IIO_SIMPLE_DUMMY without its
#   buffer and event parts: one ADC input in_voltage0_raw and one DAC output out_voltage0_raw;
#   iio_dummy_settable_adc.patch makes the ADC input take what root writes to it).
#
# The caller defines die, note, require_tool and cache_dir (absolute), optionally vm_arch
# (amd64, the default, or arm64: Debian's arm64 kernel for qemu-system-aarch64 -M virt, the
# modules cross-built with aarch64-linux-gnu-gcc), then calls
#   vm_kernel_init      picks the kernel from the package index, sets kernel_release,
#                       kernel_dir, vmlinux (for arm64: the uncompressed Image), module_root
#   prepare_kernel      downloads + builds once per kernel and module set (cached in kernel_dir;
#                       hold the cache lock)
#   vm_module_load_list MODULE...   insmod paths (/lib/modules/...), dependencies first
#   vm_arm64_guest_tools            arm64: Debian's arm64 busybox-static, gpiod, v4l-utils
#   vm_boot BOOT                    runs BOOT (the caller's function that starts QEMU in the
#                                   background, sets vm_qemu_pid and vm_guest_log, waits for
#                                   it: vm_watch_boot), once more if its kernel hung before /init
#
# module_root is a self-contained lib/modules/$kernel_release tree (depmod has run) holding
# only the modules some guest loads (vm_staged_modules), so a guest can copy it whole and use
# modprobe.

vm_kernel_lib_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
vm_arch="${vm_arch:-amd64}"

# The modules built here, from linux-source (file lists in extract_module_sources).
built_modules=(gpio-sim counter interrupt-cnt industrialio-configfs industrialio-sw-device iio_dummy)
# Every module either guest loads (their dependencies come along): the busybox guest's, the
# systemd guest's block device + root file system, and the IIO dummy. crc32c_generic: ext4
# wants crc32c and the emulated qemu64 CPU has no SSE4.2 for crc32c-intel.
vm_staged_modules=(configfs gpio-sim vivid interrupt-cnt
  virtio_pci virtio_blk ext4 crc32c_generic
  industrialio industrialio-configfs industrialio-sw-device iio_dummy)
# v4l2loopback (Debian's v4l2loopback-dkms source, arch all): a capture node a test writes
# frames into - real field images for the camera path. amd64 guests only.
if [ "$vm_arch" = amd64 ]; then
  built_modules+=(v4l2loopback)
  vm_staged_modules+=(v4l2loopback)
fi
# Loaded by guest-init.sh after it has made the gpio-sim chips, not from modules.load.
fixture_source="$vm_kernel_lib_dir/interrupt_counter_fixture.c"
# Applied to iio_simple_dummy.c before the build (the patch's header says what and why).
iio_dummy_patch="$vm_kernel_lib_dir/iio_dummy_settable_adc.patch"
# Bump when the module build steps change: a new value makes a new kernel_dir (and the old
# one is removed), so a cache never lacks a module the guest now expects.
module_build_revision=4

# --- package indices -----------------------------------------------------------------------
# amd64 packages come through the host's apt. The arm64 kernel and the arm64 guest's programs
# come through a private arm64 index in the cache (the host's sources, apt state of its own):
# `dpkg --add-architecture arm64` would change the host (cmake/toolchains/arm64-sysroot.sh
# says why the project avoids it). It is refreshed when missing or older than the host's index
# (so `apt-get update` on the host moves both), ~9 MB, a few seconds.
# shellcheck disable=SC2154 # cache_dir: the sourcing script's
vm_arm64_apt_dir() { echo "$cache_dir/apt-arm64"; }

vm_arm64_index_update() {
  local dir
  dir="$(vm_arm64_apt_dir)"
  mkdir -p "$dir/lists/partial" "$dir/cache/archives/partial"
  : >"$dir/status"
  cat >"$dir/apt.conf" <<APTCONF
APT::Architecture "arm64";
APT::Architectures { "arm64"; };
APT::Sandbox::User "$(id -un)";
Dir::State "$dir";
Dir::State::Lists "$dir/lists";
Dir::State::status "$dir/status";
Dir::Cache "$dir/cache";
Acquire::Languages "none";
APTCONF
  note "updating the arm64 package index in $dir"
  # vm_kernel_init runs before the caller takes the cache lock: runs sharing a cache queue here.
  flock "$dir/update.lock" env APT_CONFIG="$dir/apt.conf" apt-get update -qq >"$dir/update.log" 2>&1 || {
    cat "$dir/update.log" >&2
    die "apt-get update of the arm64 package index failed (network?)"
  }
  touch "$dir/updated"
}

vm_arm64_index_ensure() {
  local stamp
  stamp="$(vm_arm64_apt_dir)/updated"
  if [ ! -f "$stamp" ] ||
    [ -n "$(find /var/lib/apt/lists -maxdepth 1 -name '*_Packages*' -newer "$stamp" 2>/dev/null)" ]; then
    vm_arm64_index_update
  fi
}

# apt-cache / apt-get against the index that holds the guest's architecture (vm_arch).
vm_apt_cache() {
  if [ "$vm_arch" = arm64 ]; then APT_CONFIG="$(vm_arm64_apt_dir)/apt.conf" apt-cache "$@"; else apt-cache "$@"; fi
}
vm_apt_get() {
  if [ "$vm_arch" = arm64 ]; then APT_CONFIG="$(vm_arm64_apt_dir)/apt.conf" apt-get "$@"; else apt-get "$@"; fi
}

# arm64: Debian's arm64 busybox-static, gpiod and v4l-utils unpacked in the cache (the host's
# are amd64) -> $arm64_tools (a root holding bin/busybox and usr/bin/...). The io guest's
# initramfs and the systemd guest's stage 1 take their busybox from here. Hold the cache lock.
vm_arm64_guest_tools() {
  local packages=(busybox-static gpiod v4l-utils) versions key deb
  versions="$(vm_apt_cache show --no-all-versions "${packages[@]}" 2>/dev/null |
    sed -n 's/^Version: //p' | tr '\n' ' ')"
  [ "$(echo "$versions" | wc -w)" -eq "${#packages[@]}" ] ||
    die "the arm64 package index lacks one of ${packages[*]}"
  key="$(echo "${packages[*]} $versions" | sha256sum | cut -c1-12)"
  arm64_tools="$cache_dir/arm64-guest-tools-$key"
  [ -f "$arm64_tools/ready" ] && return 0
  find "$cache_dir" -mindepth 1 -maxdepth 1 -type d -name 'arm64-guest-tools-*' -exec rm -rf {} +
  mkdir -p "$arm64_tools/debs"
  note "downloading the arm64 ${packages[*]}"
  (cd "$arm64_tools/debs" && vm_apt_get download -q "${packages[@]}") >"$arm64_tools/download.log" 2>&1 || {
    cat "$arm64_tools/download.log" >&2
    die "apt-get download of the arm64 ${packages[*]} failed"
  }
  for deb in "$arm64_tools"/debs/*.deb; do dpkg-deb -x "$deb" "$arm64_tools/root"; done
  rm -rf "$arm64_tools/debs"
  touch "$arm64_tools/ready"
}

# --- which kernel --------------------------------------------------------------------------
# The ABI (6.1.0-NN) moves with Debian's point releases, so ask the package index.
kernel_image_package() {
  vm_apt_cache depends "linux-image-$vm_arch" 2>/dev/null |
    sed -n "s/^ *Depends: \(linux-image-[0-9][^ ]*-$vm_arch\)\$/\1/p" | head -n1 || true
}

vm_kernel_init() {
  : "${cache_dir:?the sourcing script sets cache_dir}"
  require_tool apt-get apt
  require_tool apt-cache apt
  require_tool dpkg-deb dpkg
  require_tool xz xz-utils
  require_tool modprobe kmod
  require_tool depmod kmod
  require_tool make make
  require_tool gcc gcc
  require_tool patch patch
  [ -f "$fixture_source" ] || die "$fixture_source is missing"
  case "$vm_arch" in
    amd64) ;;
    arm64) vm_arm64_index_ensure ;;
    *) die "unknown guest architecture '$vm_arch' (amd64 or arm64)" ;;
  esac
  image_package="$(kernel_image_package)"
  if [ -z "$image_package" ] && [ "$vm_arch" = arm64 ]; then
    vm_arm64_index_update
    image_package="$(kernel_image_package)"
  elif [ -z "$image_package" ] && [ "$(id -u)" -eq 0 ]; then
    note "linux-image-amd64 is not in the package index; running apt-get update"
    apt-get update -qq || die "apt-get update failed"
    image_package="$(kernel_image_package)"
  fi
  [ -n "$image_package" ] ||
    die "cannot find what linux-image-$vm_arch depends on in the package index (run apt-get update)"
  kernel_release="${image_package#linux-image-}"
  kernel_version="$(vm_apt_cache show --no-all-versions "$image_package" 2>/dev/null |
    sed -n 's/^Version: //p' || true)"
  [ -n "$kernel_version" ] || die "no version of $image_package in the package index"
  abi="${kernel_release%-"$vm_arch"}"               # 6.1.0-56
  series="$(echo "$kernel_release" | cut -d. -f1,2)" # 6.1: linux-source-6.1
  # amd64 headers depend on linux-compiler-gcc-N-x86, arm64 ones on gcc-N.
  gcc_version="$(vm_apt_cache depends "linux-headers-$kernel_release" 2>/dev/null |
    sed -n -e 's/^ *Depends: linux-compiler-gcc-\([0-9]*\)-x86$/\1/p' \
      -e 's/^ *Depends: gcc-\([0-9]*\)$/\1/p' | head -n1 || true)"
  [ -n "$gcc_version" ] || die "cannot tell which gcc linux-headers-$kernel_release is built with"
  module_make_flags=()
  if [ "$vm_arch" = arm64 ]; then
    # The headers' .kernelvariables make CC $(CROSS_COMPILE)gcc-N and ARCH arm64.
    require_tool "aarch64-linux-gnu-gcc-$gcc_version" "gcc-$gcc_version-aarch64-linux-gnu"
    module_make_flags=(ARCH=arm64 CROSS_COMPILE=aarch64-linux-gnu-)
  else
    require_tool "gcc-$gcc_version" "gcc-$gcc_version"
  fi

  module_set_key="$( (
    echo "$module_build_revision ${built_modules[*]} / ${vm_staged_modules[*]}"
    cat "$fixture_source" "$iio_dummy_patch"
  ) | sha256sum | cut -c1-12)"
  kernel_dir="$cache_dir/$kernel_release-$kernel_version-modules-$module_set_key"
  vmlinux="$kernel_dir/vmlinux"
  [ "$vm_arch" = amd64 ] || vmlinux="$kernel_dir/Image"
  module_root="$kernel_dir/modules" # lib/modules/$kernel_release with only what guests need
}

# The archive rebuilds host-side packages (linux-kbuild, linux-source) under a new Debian
# revision without the image, so the exact version may be gone while the same upstream
# release (6.1.192-3 for an image at 6.1.192-2) is there: take that, never another release.
host_package_version() { # package wanted-version -> the version to download
  local package="$1" wanted="$2" versions version
  versions="$(apt-cache madison "$package" 2>/dev/null | awk -F'|' '{gsub(/ /, "", $2); print $2}')"
  if echo "$versions" | grep -qxF "$wanted"; then echo "$wanted"; return 0; fi
  version="$(echo "$versions" | awk -v release="${wanted%-*}-" 'index($0, release) == 1' |
    sort -V | tail -n1)"
  [ -n "$version" ] ||
    die "no $package of upstream release ${wanted%-*} in the package index (has: $(echo $versions))"
  echo "$version"
}

fetch_packages() { # -> $kernel_dir/debs
  local debs="$kernel_dir/debs" package host=()
  mkdir -p "$debs"
  # The image and its headers are the guest's architecture; the common headers and the
  # sources are arch: all, and linux-kbuild (fixdep, modpost) must run here: the host's.
  local guest=("$image_package=$kernel_version" "linux-headers-$kernel_release=$kernel_version")
  for package in "linux-headers-$abi-common" "linux-kbuild-$series" "linux-source-$series"; do
    host+=("$package=$(host_package_version "$package" "$kernel_version")")
  done
  [[ " ${built_modules[*]} " == *" v4l2loopback "* ]] && host+=(v4l2loopback-dkms)
  note "downloading ${guest[*]} ${host[*]} from the Debian archive"
  (cd "$debs" && vm_apt_get download -q "${guest[@]}" && apt-get download -q "${host[@]}") \
    >"$kernel_dir/download.log" 2>&1 || {
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

# arm64: Debian's vmlinuz is the kernel's Image (QEMU boots it directly); gzip'd in some
# releases, so unpack it if it is.
extract_arm64_image() {
  local vmlinuz="$1"
  if [ "$(head -c2 "$vmlinuz" | od -An -tx1 | tr -d ' ')" = 1f8b ]; then
    gzip -dc "$vmlinuz" >"$vmlinux.tmp"
  else
    cp "$vmlinuz" "$vmlinux.tmp"
  fi
  # The arm64 Image header carries "ARM\x64" at offset 56.
  [ "$(tail -c +57 "$vmlinux.tmp" | head -c3)" = ARM ] || die "$vmlinuz is not an arm64 Image"
  mv "$vmlinux.tmp" "$vmlinux"
}

extract_module_sources() { # -> $module_src (the whole 1.3 GB tarball is read: ~10 s)
  rm -rf "$module_src" && mkdir -p "$module_src"
  local top="linux-source-$series" counter="linux-source-$series/drivers/counter"
  local iio="linux-source-$series/drivers/iio"
  # The Counter core's own headers are private; <linux/counter.h> is in the headers package.
  dpkg-deb --fsys-tarfile "$kernel_dir/debs/${top}_"*.deb |
    tar -xO "./usr/src/$top.tar.xz" | xz -dc |
    tar -x -C "$module_src" --strip-components=1 "$top/drivers/gpio/gpio-sim.c" \
      "$top/drivers/gpio/gpiolib.h" "$top/kernel/irq/irq_sim.c" \
      "$counter/counter-core.c" "$counter/counter-sysfs.c" "$counter/counter-chrdev.c" \
      "$counter/counter-sysfs.h" "$counter/counter-chrdev.h" "$counter/interrupt-cnt.c" \
      "$iio/industrialio-configfs.c" "$iio/industrialio-sw-device.c" \
      "$iio/dummy/iio_simple_dummy.c" "$iio/dummy/iio_simple_dummy.h"
}

# ROOT -> ROOT/lib/modules/$kernel_release/extra/: the modules Debian's kernel lacks
# (built_modules) and interrupt_counter_fixture.ko (test-only).
build_modules() {
  local root="$1" src="$module_src"
  local headers="$root/usr/src/linux-headers-$kernel_release"
  mv "$src/drivers/gpio/gpio-sim.c" "$src/gpio-sim-main.c"
  mv "$src/drivers/gpio/gpiolib.h" "$src/kernel/irq/irq_sim.c" "$src/drivers/counter/"* "$src/"
  mv "$src/drivers/iio/industrialio-"*.c "$src/drivers/iio/dummy/"* "$src/"
  cp "$fixture_source" "$src/"
  # irq_to_desc() is not exported to modules; generic_handle_irq() does the same lookup.
  grep -q 'handle_simple_irq(irq_to_desc(irqnum));' "$src/irq_sim.c" ||
    die "irq_sim.c no longer has the line this script patches; update build_modules"
  sed -i 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq(irqnum);/' "$src/irq_sim.c"
  # The dummy's ADC input settable from user space (the HIL plant drives it).
  patch --forward --quiet -p1 -d "$src" <"$iio_dummy_patch" ||
    die "$(basename "$iio_dummy_patch") does not apply to this kernel's iio_simple_dummy.c"
  # As drivers/{gpio,counter,iio,iio/dummy}/Makefile build them (CONFIG_GPIO_SIM, COUNTER,
  # INTERRUPT_CNT, IIO_CONFIGFS, IIO_SW_DEVICE, IIO_SIMPLE_DUMMY; not _BUFFER or _EVENTS, whose
  # code iio_simple_dummy.h stubs out).
  cat >"$src/Kbuild" <<'KBUILD'
obj-m := gpio-sim.o counter.o interrupt-cnt.o interrupt_counter_fixture.o
obj-m += industrialio-configfs.o industrialio-sw-device.o iio_dummy.o
gpio-sim-y := gpio-sim-main.o irq_sim.o
counter-y := counter-core.o counter-sysfs.o counter-chrdev.o
iio_dummy-y := iio_simple_dummy.o
KBUILD
  if [[ " ${built_modules[*]} " == *" v4l2loopback "* ]]; then
    dpkg-deb --fsys-tarfile "$kernel_dir/debs/v4l2loopback-dkms_"*.deb |
      tar -x -C "$src" --wildcards --strip-components=4 './usr/src/v4l2loopback-*/v4l2loopback*' ||
      die "cannot extract v4l2loopback's source from v4l2loopback-dkms"
    echo "obj-m += v4l2loopback.o" >>"$src/Kbuild"
  fi
  # The headers' Makefile includes the -common one by absolute /usr/src path.
  sed -i "s#^include /usr/src/#include $root/usr/src/#" "$headers/Makefile"
  note "building ${built_modules[*]} and the interrupt-cnt fixture against linux-headers-$kernel_release"
  make -C "$headers" M="$src" "${module_make_flags[@]}" -j2 modules \
    >"$kernel_dir/modules-build.log" 2>&1 || {
    cat "$kernel_dir/modules-build.log" >&2
    die "building the out-of-tree modules failed"
  }
  mkdir -p "$root/lib/modules/$kernel_release/extra"
  local module
  for module in "${built_modules[@]}" interrupt_counter_fixture; do
    cp "$src/$module.ko" "$root/lib/modules/$kernel_release/extra/"
  done
}

# ROOT MODULE... -> the .ko paths (relative to ROOT) modprobe would load, dependencies first,
# each once; built-in modules are skipped.
module_paths() {
  local root="$1" line path seen=" " m
  shift
  for m in "$@"; do
    modprobe -d "$root" -S "$kernel_release" --show-depends "$m" ||
      die "modprobe cannot resolve module '$m' in $root"
  done | while read -r line; do
    case "$line" in
      insmod\ *) ;;
      builtin\ *) continue ;;
      *) die "unexpected modprobe output: $line" ;;
    esac
    path="${line#insmod }"
    path="${path%% *}"
    path="${path#"$root"}"
    case "$seen" in *" $path "*) continue ;; esac
    seen="$seen$path "
    echo "$path"
  done
}

# ROOT -> $module_root: vm_staged_modules and their dependencies, then depmod there.
stage_modules() {
  local root="$1" path
  depmod -b "$root" "$kernel_release"
  rm -rf "$module_root" && mkdir -p "$module_root/lib/modules/$kernel_release"
  while read -r path; do
    mkdir -p "$module_root$(dirname "$path")"
    cp "$root$path" "$module_root$path"
  done < <(module_paths "$root" "${vm_staged_modules[@]}")
  local fixture="lib/modules/$kernel_release/extra/interrupt_counter_fixture.ko"
  cp "$root/$fixture" "$module_root/$fixture"
  # modprobe must know which modules are built in (e.g. it would look for a missing .ko).
  cp "$root/lib/modules/$kernel_release/"modules.{builtin,builtin.modinfo,order} \
    "$module_root/lib/modules/$kernel_release/"
  depmod -b "$module_root" "$kernel_release"
}

vm_module_load_list() { # MODULE... -> insmod paths (/lib/modules/...), dependencies first, once
  module_paths "$module_root" "$@"
}

prepare_kernel() {
  [ -f "$kernel_dir/ready" ] && return 0
  local started=$SECONDS root="$kernel_dir/root" deb
  rm -rf "$kernel_dir" && mkdir -p "$kernel_dir"
  module_src="$kernel_dir/module-src"
  fetch_packages
  note "unpacking the kernel packages and the module sources"
  # Both are single-threaded xz streams: unpack them side by side.
  extract_module_sources &
  local sources_job=$!
  mkdir -p "$root"
  for deb in "$kernel_dir"/debs/linux-{image,headers,kbuild}-*.deb; do dpkg-deb -x "$deb" "$root"; done
  if [ "$vm_arch" = arm64 ]; then
    extract_arm64_image "$root/boot/vmlinuz-$kernel_release"
  else
    extract_vmlinux "$root/boot/vmlinuz-$kernel_release"
  fi
  wait "$sources_job" || die "extracting the module sources from linux-source-$series failed"
  build_modules "$root"
  stage_modules "$root"
  rm -rf "$root" "$module_src" "$kernel_dir/debs" # keep what boots, ~80 MB
  # Keep only this kernel: older ABIs and module sets are never booted again. Only kernel
  # directories of this architecture: the cache also holds other guests' files (e.g. the
  # systemd guest's rootfs, the other architecture's kernel).
  find "$cache_dir" -mindepth 1 -maxdepth 1 -type d -name "*-$vm_arch-*-modules-*" \
    ! -path "$kernel_dir" -exec rm -rf {} +
  touch "$kernel_dir/ready"
  note "kernel $kernel_release ($kernel_version) prepared in $((SECONDS - started)) s"
}

# --- booting --------------------------------------------------------------------------------
# Each guest's PID 1 prints WEEDSPRAY-VM-INIT first. A kernel that has not started it within
# vm_init_deadline_s has hung in its own boot: TCG's emulated SMP bring-up hangs now and then,
# with no console output the whole timeout long. /init starts 2-3 s after QEMU does here (amd64
# and arm64), 5 s with both host cores busy.
vm_init_deadline_s=120

# Waits until $vm_guest_log shows /init started or QEMU ($vm_qemu_pid, under timeout) ends;
# past the deadline without it, stops QEMU. Sets vm_reached_init (1 or 0).
vm_watch_boot() {
  local waited=0
  vm_reached_init=0
  while kill -0 "$vm_qemu_pid" 2>/dev/null; do
    if grep -qa 'WEEDSPRAY-VM-INIT' "$vm_guest_log"; then
      vm_reached_init=1
      note "the guest started /init after $waited s"
      return 0
    fi
    if ((waited >= vm_init_deadline_s)); then
      kill "$vm_qemu_pid" 2>/dev/null || true # timeout passes the signal on to QEMU
      return 0
    fi
    sleep 1
    waited=$((waited + 1))
  done
  if grep -qa 'WEEDSPRAY-VM-INIT' "$vm_guest_log"; then vm_reached_init=1; fi
  return 0
}

# Runs BOOT, and once more when the guest's kernel never started /init; a hang after /init, or
# a second one before it, is the caller's failure. Returns BOOT's last status.
vm_boot() {
  local status=0
  "$1" || status=$?
  if ((!vm_reached_init)); then
    note "the guest kernel did not start /init within $vm_init_deadline_s s (QEMU status $status): its boot hung; booting once more"
    cat -v "$vm_guest_log" >&2
    status=0
    "$1" || status=$?
  fi
  return "$status"
}
