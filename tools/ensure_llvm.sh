#!/usr/bin/env bash
# Make sure a system libLLVM >= 15 is present: Dr.Jit's LLVM backend (Mitsuba 3 and Sionna RT on
# the CPU) aborts with "Cannot select" on Debian 12's default libLLVM 14.
set -euo pipefail
have_llvm() {
  ldconfig -p 2>/dev/null | grep -qE 'libLLVM(-|\.so\.)(1[5-9]|[2-9][0-9])' && return 0
  ls /usr/lib/*/libLLVM-1[5-9]*.so* /usr/lib/*/libLLVM.so.1[5-9]* /usr/lib/*/libLLVM-2[0-9]*.so* >/dev/null 2>&1
}
if have_llvm; then exit 0; fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null; then
  echo "emscatter: installing libllvm19 (Dr.Jit's CPU backend needs libLLVM >= 15)" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq >/dev/null
  apt-get install -y -qq libllvm19 >/dev/null || apt-get install -y -qq libllvm15 >/dev/null
  have_llvm && exit 0
fi
cat >&2 <<'MSG'
emscatter: no system libLLVM >= 15 found. Mitsuba 3 and Sionna RT run on the CPU through Dr.Jit's
LLVM backend, which needs it. Install one, e.g. on Debian/Ubuntu as root:
    apt-get update && apt-get install -y libllvm19
(or point DRJIT_LIBLLVM_PATH at an existing libLLVM.so >= 15). Then run the command again.
MSG
exit 1
