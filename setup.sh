#!/usr/bin/env bash
# dpc31emu setup: installs the missing Debian 12 packages (as root; otherwise prints the exact
# apt-get line and stops), then configures and builds into build/. Safe to run again.
set -euo pipefail
cd "$(dirname "$0")"

# Build: compiler, CMake, Verilator and the libraries. Checks in the test suite: gtkwave
# (vcd2fst / fst2vcd; the GUI under xvfb's Xvfb for our save files), sigrok-cli (UART and
# PROFIBUS decode of our waveforms), pulseview (the GUI under Xvfb: the demo's capture with its
# session's decoders), tshark (our pcapng captures), python3 (a DP master on the
# pty of dpc31 bridge). The fuzz build of test.sh: clang with its sanitizer and libFuzzer
# runtimes (libclang-rt-14-dev), ninja. The install test (Install.*):
# pkgconf (pkg-config), and for the Debian package (cpack -G DEB) dpkg-dev and file. GNU
# parallel and rsync (its --return over ssh): the sharded regression's test and recipes
# (docs/regression.md). sdcc (sdas8051, sdld) and sdcc-ucsim (s51): the 80C32 test programs and
# their cross-check against ucsim (docs/cpu.md). The Python module and its pytest examples
# (docs/python.md): pybind11-dev, python3-dev, python3-pytest; the SystemC TLM-2.0 model
# (docs/systemc.md): libsystemc-dev.
packages=(cmake g++ make ccache verilator libfmt-dev libcli11-dev nlohmann-json3-dev libgtest-dev
  libbenchmark-dev zlib1g-dev gtkwave xvfb sigrok-cli pulseview tshark python3 clang
  libclang-rt-14-dev ninja-build pkgconf dpkg-dev file parallel rsync sdcc sdcc-ucsim pybind11-dev
  python3-dev python3-pytest libsystemc-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  if [ "$(id -u)" -eq 0 ]; then
    echo "setup: installing ${missing[*]}"
    apt-get update -q
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
  else
    echo "setup: missing Debian packages. Install them as root with:" >&2
    echo "  apt-get install -y --no-install-recommends ${missing[*]}" >&2
    exit 1
  fi
fi

# Our development build: warnings in our code are errors (a user's plain cmake build leaves
# DPC31_WERROR off). Debug information is line tables only (-g1: backtraces, perf and sanitizer
# reports keep file:line; gdb loses locals), which keeps a fresh build within 5 minutes on two
# cores (docs/install.md, "Build time"); configure with -g for a debugging session.
# DPC31_BUILD_DIR: another build directory than build/ (dpc31 bench --build times a fresh one).
build_dir=${DPC31_BUILD_DIR:-build}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DDPC31_WERROR=ON \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG"
cmake --build "$build_dir" -j "$(nproc)"
