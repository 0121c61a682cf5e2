#!/usr/bin/env bash
# Run SCRIPT on the qemu tier's MicroPython (tools/build-micropython-tiers.sh builds it: the
# qemu port's MPS2_AN385 board, ARMv6-M viper code as an RP2040 runs) under qemu-system-arm,
# with DIR mounted as the device's working directory by mpremote over the emulated UART.
#
#   run-qemu-mps2.sh DIR SCRIPT.py      (DIR "-": no mount)
#
# FW: the firmware (default: micropython-qemu-mps2-an385-armv6m.elf beside this script);
# MPREMOTE: the mpremote to use; QEMU_ICOUNT=0 runs the guest with -icount shift=0, so its
# clock counts executed instructions (1 ns each) instead of host time.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
dir=${1:?usage: run-qemu-mps2.sh DIR|- SCRIPT.py}
script=${2:?usage: run-qemu-mps2.sh DIR|- SCRIPT.py}
fw=${FW:-$here/micropython-qemu-mps2-an385-armv6m.elf}
mpremote=${MPREMOTE:-mpremote}
[ -f "$fw" ] || { echo "run-qemu-mps2: no firmware at $fw (tools/build-micropython-tiers.sh qemu)" >&2; exit 1; }
extra=()
[ -n "${QEMU_ICOUNT:-}" ] && extra=(-icount "shift=$QEMU_ICOUNT")
log=$(mktemp)
qemu-system-arm -machine mps2-an385 -nographic -monitor null -semihosting -serial pty \
  "${extra[@]}" -kernel "$fw" > "$log" 2>&1 &
qpid=$!
trap 'kill $qpid 2>/dev/null || true; rm -f "$log"' EXIT
pty=
for _ in $(seq 100); do
  pty=$(grep -o '/dev/pts/[0-9]*' "$log" | head -1 || true)
  [ -n "$pty" ] && break
  sleep 0.1
done
[ -n "$pty" ] || { echo "run-qemu-mps2: qemu did not start:" >&2; cat "$log" >&2; exit 1; }
sleep 1  # the firmware's REPL comes up before mpremote opens the pty
if [ "$dir" = - ]; then
  "$mpremote" connect "$pty" run "$script"
else
  "$mpremote" connect "$pty" mount "$dir" run "$script"
fi
