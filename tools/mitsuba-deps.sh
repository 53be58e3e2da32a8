#!/usr/bin/env bash
# Installs what tools/mitsuba_check.py needs on a fresh Debian 12 machine, idempotently:
#   - the PyPI packages `mitsuba` (brings `drjit`) and `numpy`, with pip;
#   - a libLLVM >= 16 for Dr.Jit's LLVM backend (LLVM 15, Debian 12's default, fails with
#     "Cannot select fmaximum"). Debian 12's main archive carries libllvm19 and libllvm16; the
#     newest one installable is chosen (19 preferred), no backports needed.
# Prints the library path as its last line, in the form `DRJIT_LIBLLVM_PATH=/path/libLLVM.so.N`;
# tools/mitsuba-compare and tools/mitsuba_check.py find the library themselves, so exporting it
# is only needed for running Mitsuba by hand.
# Needs root or sudo for apt (only when a package is missing). Python: `python3` unless $PYTHON.
set -euo pipefail
PYTHON="${PYTHON:-python3}"
sudo=""
[ "$(id -u)" = 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }

llvm_pkg=""
for v in 20 19 18 17 16; do
  if installed "libllvm$v"; then llvm_pkg="libllvm$v"; break; fi
done
if [ -z "$llvm_pkg" ]; then
  $sudo apt-get update -qq
  for v in 20 19 18 17 16; do
    cand="$(apt-cache policy "libllvm$v" 2>/dev/null | awk '/Candidate:/ {print $2}')"
    if [ -n "$cand" ] && [ "$cand" != "(none)" ]; then llvm_pkg="libllvm$v"; break; fi
  done
  [ -n "$llvm_pkg" ] || { echo "mitsuba-deps: no libllvm >= 16 installable (try bookworm-backports)" >&2; exit 1; }
  echo "installing: $llvm_pkg" >&2
  $sudo apt-get install -y -qq --no-install-recommends "$llvm_pkg" >/dev/null
fi
lib="$(dpkg -L "$llvm_pkg" | grep -E '/libLLVM(-[0-9]+)?\.so(\.[0-9.]+)?$' | head -n1)"
[ -n "$lib" ] && [ -e "$lib" ] || { echo "mitsuba-deps: libLLVM not found in $llvm_pkg" >&2; exit 1; }

if ! "$PYTHON" -c 'import mitsuba, numpy' 2>/dev/null; then
  echo "installing: mitsuba numpy (pip)" >&2
  "$PYTHON" -m pip install -q mitsuba numpy
fi
echo "mitsuba $("$PYTHON" -c 'import mitsuba; print(mitsuba.__version__)'), $llvm_pkg" >&2
echo "DRJIT_LIBLLVM_PATH=$lib"
