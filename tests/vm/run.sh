#!/usr/bin/env bash
# VM tier: boot the Debian 6.1 kernel under QEMU (virtme-ng, TCG) on the
# host's root file system, run tests/vm/guest.sh in it (vcan, can-isotp,
# gpio-sim, then tests/vm/test_guest.py), print the guest's pytest output and
# exit with pytest's status. Never skips: when the guest cannot run, it says
# why and exits 1.
#
# Usage: tests/vm/run.sh [PYTEST ARGS...]   (e.g. -k isotp)
# Environment: LS_BUILD_DIR (default <repo>/build), LS_VENV (<repo>/.venv),
#   LS_VM_TIMEOUT seconds for boot + checks (default 540),
#   LS_VM_KERNEL a kernel image (default the newest /boot/vmlinuz-6.1*).
# Run tests/vm/setup.sh first (.ci/vm does).
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
build=$(realpath -m "${LS_BUILD_DIR:-$repo/build}")
venv=${LS_VENV:-$repo/.venv}
limit=${LS_VM_TIMEOUT:-540}

die() { echo "vm: error: $*" >&2; exit 1; }

kimg=${LS_VM_KERNEL:-$(ls /boot/vmlinuz-6.1* 2>/dev/null | sort -V | tail -n1)}
[ -n "$kimg" ] && [ -f "$kimg" ] || die "no guest kernel image (/boot/vmlinuz-6.1*): run tests/vm/setup.sh"
kver=${kimg#/boot/vmlinuz-}
[ -d "/lib/modules/$kver" ] || die "no modules for $kver in /lib/modules: reinstall linux-image-$kver"
command -v qemu-system-x86_64 >/dev/null || die "qemu-system-x86_64 missing: run tests/vm/setup.sh (Debian qemu-system-x86)"
[ -x "$venv/bin/vng" ] || die "virtme-ng missing in $venv: run tests/vm/setup.sh"
"$venv/bin/python" -c 'import evdev' 2>/dev/null || die "python evdev missing in $venv: run tests/vm/setup.sh"
ko=$here/.cache/gpio-sim-$kver/gpio_sim_oot.ko
[ -f "$ko" ] || die "no gpio-sim module for $kver at $ko: run tests/vm/setup.sh"
[ -x "$build/bin/isotp_socketcan_echo" ] || die "$build/bin/isotp_socketcan_echo missing: build first (bash .ci/build)"

out=$(mktemp -d /tmp/ls-vm.XXXXXX)
console=$out/console.log
echo "vm: booting $kimg under QEMU (TCG, no KVM), limit $limit s; output in $out"
now_ms() { echo $(( $(date +%s%N) / 1000000 )); }
t0=$(now_ms)
# vng runs virtme-run from its own bin dir; setsid gives the guest its own
# process group so that a time-out stops QEMU and everything under it.
PATH=$venv/bin:$PATH setsid "$venv/bin/vng" --run "$kimg" --user root --disable-kvm \
  --rwdir "$out" -- "$here/guest.sh" "$out" "$repo" "$build" "$venv" "$ko" "$@" \
  </dev/null >"$console" 2>&1 &
pid=$!

elapsed_ms() { echo $(( $(now_ms) - t0 )); }
secs() { local ms=$(( $1 < 0 ? 0 : $1 )); printf '%d.%d' $(( ms / 1000 )) $(( ms % 1000 / 100 )); }
t_boot=""
status=""
while kill -0 "$pid" 2>/dev/null; do
  if [ -z "$t_boot" ] && [ -f "$out/started" ]; then
    t_boot=$(elapsed_ms)
  fi
  if [ "$(elapsed_ms)" -gt $(( limit * 1000 )) ]; then
    kill -TERM -- "-$pid" 2>/dev/null
    sleep 2
    kill -KILL -- "-$pid" 2>/dev/null
    status="timeout after $limit s"
    break
  fi
  sleep 0.5
done
wait "$pid" 2>/dev/null
vng_rc=$?
t_end=$(elapsed_ms)
[ -z "$t_boot" ] && [ -f "$out/started" ] && t_boot=$t_end

if [ -f "$out/pytest.log" ]; then
  echo "== guest pytest =="
  cat "$out/pytest.log"
fi
# Guest-side duration of set-up + pytest, by the guest's own clock (uptime).
guest_ms() { awk '{ printf "%d", $1 * 1000 }' "$1"; }
if [ -n "$t_boot" ] && [ -f "$out/finished" ]; then
  g=$(( $(guest_ms "$out/finished") - $(guest_ms "$out/started") ))
  echo "vm: timing: boot $(secs "$t_boot") s, guest set-up + checks $(secs "$g") s," \
       "shutdown $(secs $(( t_end - t_boot - g ))) s, total $(secs "$t_end") s"
elif [ -n "$t_boot" ]; then
  echo "vm: timing: boot $(secs "$t_boot") s, then $(secs $(( t_end - t_boot ))) s, total $(secs "$t_end") s"
else
  echo "vm: timing: the guest script never started; total $(secs "$t_end") s"
fi

if [ -f "$out/pytest.rc" ]; then
  rc=$(cat "$out/pytest.rc")
  if [ "$rc" = 0 ]; then
    echo "vm: passed"
    rm -rf "$out"
  else
    echo "vm: FAILED: guest pytest exited with $rc (logs of landscaped and the console in $out)"
  fi
  exit "$rc"
fi
echo "== guest console (last 40 lines) =="
tail -n 40 "$console"
if [ -n "$status" ]; then
  die "the guest did not finish: $status (raise LS_VM_TIMEOUT, or see $console)"
elif [ -f "$out/setup_error" ]; then
  die "guest set-up failed: $(cat "$out/setup_error")"
elif [ ! -f "$out/started" ]; then
  die "the guest did not boot to its script (vng exit $vng_rc; console above)"
else
  die "the guest stopped before pytest finished (vng exit $vng_rc; console above)"
fi
