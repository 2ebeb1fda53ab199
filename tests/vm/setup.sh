#!/usr/bin/env bash
# VM tier set-up (idempotent, root on Debian 12): QEMU, a Debian 6.1 kernel
# with its modules and headers (the guest's kernel, never the host's), can-utils,
# libgpiod tools, virtme-ng and python evdev in the project venv, and the gpio-sim module built
# out of tree (Debian's kernels lack CONFIG_GPIO_SIM) into tests/vm/.cache/.
# Fast when already done. Prints the guest kernel image path on its last line.
#
# Environment: LS_VENV (default <repo>/.venv; created by .ci/setup).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
venv=${LS_VENV:-$repo/.venv}
cache=$here/.cache

log() { echo "vm-setup: $*" >&2; }
die() { echo "vm-setup: error: $*" >&2; exit 1; }

is_installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }

apt_install() {
  local missing=()
  for p in "$@"; do is_installed "$p" || missing+=("$p"); done
  [ ${#missing[@]} -eq 0 ] && return 0
  [ "$(id -u)" -eq 0 ] || die "run as root, or install these Debian packages first: ${missing[*]}"
  log "installing Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  if [ -z "${LS_VM_APT_UPDATED:-}" ]; then apt-get update -qq; LS_VM_APT_UPDATED=1; fi
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

apt_install qemu-system-x86 linux-image-amd64 linux-source-6.1 kmod iproute2 can-utils gpiod \
  busybox-static xz-utils make gcc

# The guest kernel: the newest Debian 6.1 image under /boot.
kimg=$(ls /boot/vmlinuz-6.1* 2>/dev/null | sort -V | tail -n1 || true)
[ -n "$kimg" ] || die "no /boot/vmlinuz-6.1* after installing linux-image-amd64"
kver=${kimg#/boot/vmlinuz-}
[ -d "/lib/modules/$kver/kernel/drivers/net/can" ] || die "/lib/modules/$kver has no CAN modules"
apt_install "linux-headers-$kver"

# virtme-ng boots the kernel on the host's root file system.
[ -x "$venv/bin/python" ] || die "no Python venv at $venv: run .ci/setup first"
if [ ! -x "$venv/bin/vng" ]; then
  log "installing virtme-ng into $venv"
  "$venv/bin/pip" install -q virtme-ng
fi
# python evdev: the guest's virtual gamepad and 6-DOF device (uinput). Pinned
# in the [dev] extra; installed here too for a venv made before it was.
if ! "$venv/bin/python" -c 'import evdev' 2>/dev/null; then
  log "installing evdev into $venv"
  "$venv/bin/pip" install -q -c "$repo/host_tools/constraints.txt" evdev
fi

# gpio-sim out of tree: gpio-sim.c + gpiolib.h + irq_sim.c as one module.
# irq_sim.c's exports are dropped (the symbols stay inside this module) and
# handle_simple_irq(irq_to_desc(n)) becomes generic_handle_irq(n), because
# irq_to_desc is not exported to modules.
ko=$cache/gpio-sim-$kver/gpio_sim_oot.ko
if [ ! -f "$ko" ]; then
  src=$(ls /usr/src/linux-source-6.1.tar.* 2>/dev/null | head -n1 || true)
  [ -n "$src" ] || die "linux-source-6.1 installed no /usr/src/linux-source-6.1.tar.*"
  bdir=$cache/gpio-sim-$kver.build
  rm -rf "$bdir"; mkdir -p "$bdir"
  log "extracting gpio-sim sources from $src (once)"
  tar -xf "$src" -C "$bdir" --strip-components=1 \
    linux-source-6.1/drivers/gpio/gpio-sim.c linux-source-6.1/drivers/gpio/gpiolib.h \
    linux-source-6.1/kernel/irq/irq_sim.c
  cp "$bdir/drivers/gpio/gpio-sim.c" "$bdir/drivers/gpio/gpiolib.h" "$bdir/kernel/irq/irq_sim.c" "$bdir/"
  sed -i '/^EXPORT_SYMBOL_GPL(/d' "$bdir/irq_sim.c"
  sed -i 's/handle_simple_irq(irq_to_desc(\([a-z_]*\)))/generic_handle_irq(\1)/' "$bdir/irq_sim.c"
  grep -q 'generic_handle_irq(' "$bdir/irq_sim.c" || die "irq_sim.c: handle_simple_irq(irq_to_desc()) not found to patch"
  ! grep -q 'EXPORT_SYMBOL' "$bdir/irq_sim.c" || die "irq_sim.c: exports left after patching"
  printf 'obj-m := gpio_sim_oot.o\ngpio_sim_oot-y := gpio-sim.o irq_sim.o\n' > "$bdir/Kbuild"
  log "building gpio_sim_oot.ko against /lib/modules/$kver/build"
  make -s -C "/lib/modules/$kver/build" M="$bdir" modules >"$bdir/build.log" 2>&1 \
    || { cat "$bdir/build.log" >&2; die "gpio-sim module build failed (log above)"; }
  mkdir -p "$(dirname "$ko")"
  cp "$bdir/gpio_sim_oot.ko" "$ko"
  rm -rf "$bdir"
fi
log "ok: kernel $kimg, gpio-sim module $ko"
echo "$kimg"
