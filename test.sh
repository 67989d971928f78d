#!/usr/bin/env bash
# The whole test suite, as CI runs it (.ci/run): setup.sh installs what is missing and builds
# build/; the suite runs there; then the sanitizer build (CMakePresets.json, preset asan:
# AddressSanitizer + UndefinedBehaviorSanitizer in build-asan/, docs/sanitizers.md) is
# configured, built and its suite run. Exit code 0 only if both suites pass.
set -uo pipefail
cd "$(dirname "$0")"

./setup.sh || exit $?

start=$SECONDS
ctest --test-dir build --output-on-failure -j 2
normal=$?
echo "test.sh: normal suite exit code $normal after $((SECONDS - start)) s"

start=$SECONDS
asan=1
if cmake --preset asan && cmake --build --preset asan -j "$(nproc)"; then
  echo "test.sh: asan build took $((SECONDS - start)) s"
  start=$SECONDS
  ctest --preset asan
  asan=$?
  echo "test.sh: asan suite exit code $asan after $((SECONDS - start)) s"
else
  echo "test.sh: the asan build failed"
fi

[ "$normal" -eq 0 ] && [ "$asan" -eq 0 ]
