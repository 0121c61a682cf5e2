#!/usr/bin/env bash
# Build the MicroPython interpreters of the 32-bit test tiers (tests/mp.py) from a MicroPython
# source tree: the registries carry no 32-bit unix port with the native emitter and no
# Cortex-M firmware, so the repository carries this recipe and the pinned version instead.
#
#   MICROPYTHON_SRC=/path/to/micropython tools/build-micropython-tiers.sh [x86|qemu|all]
#
# MICROPYTHON_SRC: a checkout of MicroPython at PIN_TAG (PIN_COMMIT), with its
# lib/micropython-lib submodule (git submodule update --init lib/micropython-lib; the unix
# port freezes mip, requests and asyncio from it). x86 needs gcc with -m32 (Debian:
# gcc-multilib); qemu needs arm-none-eabi-gcc (Debian: gcc-arm-none-eabi, libnewlib-arm-none-eabi).
# Writes into ECOMPASS_TOOLS (default: build/tools in this repository), where tests/mp.py
# looks for them:
#   micropython-x86-32   the unix port, standard variant, 32-bit (31-bit small ints) with the
#                        x86 native/viper emitter, static ("x86-32" tier)
#   mpy-cross-x86-32     mpy-cross of the same tree, 32-bit, static (make bench's .mpy files)
#   micropython-qemu-mps2-an385-armv6m.elf  the qemu port, MPS2_AN385, 2 MB heap, viper
#                        emitting ARMv6-M Thumb only, as an RP2040 runs ("arm" tier, make test-arm)
#   run-qemu-mps2.sh     runs a script on it under qemu-system-arm (see the file)
# The build happens in a copy of the tree (the checkout is left as it is).
set -euo pipefail

PIN_TAG=v1.28.0
PIN_COMMIT=e0e9fbb17ed6fd06bb76e266ae554784c9c80804
# the banner's date is the pinned commit's (its commit time), whatever today is: with the same
# compiler (Debian 12's gcc 12.2) mpy-cross comes out the same bytes on every machine, and the
# unix port too but for its 20-byte GNU build-id, which hashes the build's temporary paths
export SOURCE_DATE_EPOCH=${SOURCE_DATE_EPOCH:-1775481169}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT=${ECOMPASS_TOOLS:-$ROOT/build/tools}
what=${1:-all}

die() { echo "build-micropython-tiers: $*" >&2; exit 2; }

case "$what" in x86|qemu|all) ;; *) die "usage: MICROPYTHON_SRC=DIR $0 [x86|qemu|all]" ;; esac
[ -n "${MICROPYTHON_SRC:-}" ] || die "set MICROPYTHON_SRC to a MicroPython $PIN_TAG checkout"
[ -f "$MICROPYTHON_SRC/py/mpconfig.h" ] || die "$MICROPYTHON_SRC is not a MicroPython source tree"
ver=$(sed -n 's/^#define MICROPY_VERSION_\(MAJOR\|MINOR\|MICRO\) (*\([0-9]*\))*$/\2/p' \
      "$MICROPYTHON_SRC/py/mpconfig.h" | paste -sd.)
[ "v$ver" = "$PIN_TAG" ] || die "$MICROPYTHON_SRC is MicroPython v$ver, the tiers pin $PIN_TAG ($PIN_COMMIT)"
if git -C "$MICROPYTHON_SRC" rev-parse HEAD >/dev/null 2>&1; then
  head=$(git -C "$MICROPYTHON_SRC" rev-parse HEAD)
  [ "$head" = "$PIN_COMMIT" ] || die "$MICROPYTHON_SRC is at $head, the tiers pin $PIN_COMMIT ($PIN_TAG)"
fi
[ -f "$MICROPYTHON_SRC/lib/micropython-lib/README.md" ] || \
  die "lib/micropython-lib is empty: git -C $MICROPYTHON_SRC submodule update --init lib/micropython-lib"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -a "$MICROPYTHON_SRC/." "$work/src"
mkdir -p "$OUT"
jobs=$(nproc 2>/dev/null || echo 2)

if [ "$what" != qemu ]; then
  echo | gcc -m32 -x c -c -o /dev/null - 2>/dev/null || die "gcc -m32 does not work (Debian: apt-get install gcc-multilib)"
  make -s -C "$work/src/mpy-cross" -j"$jobs" CFLAGS_EXTRA=-m32 LDFLAGS_EXTRA="-m32 -static" \
    PROG=mpy-cross-x86-32
  make -s -C "$work/src/ports/unix" -j"$jobs" VARIANT=standard MICROPY_FORCE_32BIT=1 \
    LDFLAGS_EXTRA=-static MICROPY_PY_FFI=0 MICROPY_PY_BTREE=0 MICROPY_PY_SSL=0 \
    MICROPY_SSL_AXTLS=0 MICROPY_SSL_MBEDTLS=0
  cp "$work/src/mpy-cross/build/mpy-cross-x86-32" "$OUT/mpy-cross-x86-32"
  cp "$work/src/ports/unix/build-standard/micropython" "$OUT/micropython-x86-32"
  echo "built $OUT/micropython-x86-32 and $OUT/mpy-cross-x86-32"
fi
if [ "$what" != x86 ]; then
  command -v arm-none-eabi-gcc >/dev/null || \
    die "arm-none-eabi-gcc not found (Debian: apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi)"
  make -s -C "$work/src/ports/qemu" -j"$jobs" BOARD=MPS2_AN385 MICROPY_HEAP_SIZE=2097152 \
    CFLAGS_EXTRA=-DMICROPY_EMIT_THUMB_ARMV7M=0
  arm-none-eabi-strip -o "$OUT/micropython-qemu-mps2-an385-armv6m.elf" \
    "$work/src/ports/qemu/build-MPS2_AN385/firmware.elf"
  cp "$ROOT/tools/run-qemu-mps2.sh" "$OUT/run-qemu-mps2.sh"
  echo "built $OUT/micropython-qemu-mps2-an385-armv6m.elf"
fi
