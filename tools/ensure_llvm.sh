#!/usr/bin/env bash
# Make sure a system libLLVM >= 17 is present: Dr.Jit's LLVM backend (Mitsuba 3 and Sionna RT on
# the CPU) aborts with "Cannot select" on Debian 12's default libLLVM 14.
set -euo pipefail
# Seen on Debian 12: with libllvm14 and libllvm15 installed Dr.Jit still aborted ("Cannot select");
# libllvm19 fixed it. So we look for LLVM >= 17 and install libllvm19 otherwise.
have_llvm() {
  [ -n "${DRJIT_LIBLLVM_PATH:-}" ] && [ -f "$DRJIT_LIBLLVM_PATH" ] && return 0
  local f
  for f in /usr/lib/*/libLLVM.so.1[7-9]* /usr/lib/*/libLLVM.so.[2-9][0-9]* \
           /usr/lib/*/libLLVM-1[7-9]*.so* /usr/lib/*/libLLVM-[2-9][0-9]*.so*; do
    [ -e "$f" ] && return 0
  done
  return 1
}
if have_llvm; then exit 0; fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null; then
  echo "emscatter: installing libllvm19 (Dr.Jit's CPU backend needs libLLVM >= 17)" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq >/dev/null
  apt-get install -y -qq libllvm19 >/dev/null
  have_llvm && exit 0
fi
cat >&2 <<'MSG'
emscatter: no system libLLVM >= 17 found. Mitsuba 3 and Sionna RT run on the CPU through Dr.Jit's
LLVM backend, which needs it. Install one, e.g. on Debian/Ubuntu as root:
    apt-get update && apt-get install -y libllvm19
(or point DRJIT_LIBLLVM_PATH at an existing libLLVM.so >= 17). Then run the command again.
MSG
exit 1
