#!/bin/bash
# Runs inside the VM guest (as root, host root fs read-only): sets up two vcan
# buses (vcan0 for the supervisors, vcan1 for the CiA 402 drives), a gpio-sim
# chip and uinput, then runs tests/vm/test_guest.py with the project venv's
# pytest (-rP: with the figures the passing tests print). Writes into OUT (a
# writable dir shared with the host):
#   started       written first: the host measures the boot time by it
#   setup_error   the set-up step that failed (then no pytest.rc)
#   pytest.log    pytest's output;  pytest.rc  its exit status
# Usage: guest.sh OUT REPO BUILD VENV GPIO_SIM_KO [PYTEST ARGS...]
set -u
out=$1 repo=$2 build=$3 venv=$4 ko=$5
shift 5
cat /proc/uptime > "$out/started"

fail() {
  echo "guest: set-up failed: $*" | tee "$out/setup_error"
  exit 1
}
run() { "$@" || fail "$* (exit $?)"; }

echo "guest: kernel $(uname -r), $(nproc) CPUs, up $(cut -d' ' -f1 /proc/uptime) s"

# Real SocketCAN: virtual CAN buses with the kernel's CAN_RAW and CAN_ISOTP:
# vcan0 for the supervisors, vcan1 the drive bus (docs/deploy.md "Drives": the
# drives on a bus of their own).
run modprobe vcan
run modprobe can-raw
run modprobe can-isotp
for ifname in vcan0 vcan1; do
  run ip link add dev "$ifname" type vcan
  run ip link set "$ifname" up
done

# Real GPIO: one gpio-sim chip, one bank of 8 lines (the out-of-tree module).
run modprobe configfs
mountpoint -q /sys/kernel/config || run mount -t configfs none /sys/kernel/config
[ -f "$ko" ] || fail "no gpio-sim module at $ko (run tests/vm/setup.sh)"
run insmod "$ko"
cfs=/sys/kernel/config/gpio-sim/ls-vm
run mkdir "$cfs"
run mkdir "$cfs/bank0"
echo 8 > "$cfs/bank0/num_lines" || fail "gpio-sim: num_lines"
echo ls-vm-bank0 > "$cfs/bank0/label" || fail "gpio-sim: label"
echo 1 > "$cfs/live" || fail "gpio-sim: live"
chip=$(cat "$cfs/bank0/chip_name") dev=$(cat "$cfs/dev_name")
[ -e "/dev/$chip" ] || fail "gpio-sim: /dev/$chip did not appear"
echo "guest: vcan0 and vcan1 up; gpio-sim $dev: /dev/$chip, 8 lines"

# Input devices: evdev (the /dev/input/event* nodes) and uinput, through which
# the tests make a virtual gamepad and a virtual 6-DOF device.
run modprobe evdev
run modprobe uinput
[ -c /dev/uinput ] || fail "uinput: /dev/uinput did not appear"

export LS_VM_CAN_IF=vcan0 LS_VM_DRIVE_IF=vcan1 LS_VM_GPIO_CHIP=$chip LS_VM_GPIO_SYSFS=/sys/devices/platform/$dev/$chip
export LS_BUILD_DIR=$build LS_VM_OUT=$out PYTHONDONTWRITEBYTECODE=1 PATH=$venv/bin:$PATH
cd "$repo" || fail "cd $repo"
echo "guest: running pytest at $(cut -d' ' -f1 /proc/uptime) s"
"$venv/bin/python" -m pytest -v -rfEsxP -p no:cacheprovider --junitxml="$out/junit.xml" \
  tests/vm/test_guest.py "$@" > "$out/pytest.log" 2>&1
echo $? > "$out/pytest.rc"
cat /proc/uptime > "$out/finished"
