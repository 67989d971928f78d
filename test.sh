#!/usr/bin/env bash
# The whole test suite, as CI runs it (.ci/run): setup.sh installs what is missing and builds
# build/; the suite runs there; then the fuzz build (clang, ASan + UBSan + libFuzzer, only what
# the fuzz targets need, in build-fuzz/, docs/robustness.md) is built and each fuzz target runs
# for 30 s (CTest tests Fuzz.*); then the sanitizer build (CMakePresets.json, preset asan:
# AddressSanitizer + UndefinedBehaviorSanitizer in build-asan/, docs/sanitizers.md) is
# configured, built and its suite run; last the second compiler (preset clang-release: clang++,
# Release, in build-clang/, docs/install.md) is built and its suite run. Exit code 0 only if all
# four pass. At the end it names each suite's failed tests again with the end of their output
# (CI shows only the last part of what this prints).
set -uo pipefail
cd "$(dirname "$0")"

./setup.sh || exit $?

# Each suite's failed tests, named again at the end: CI shows only the last part of the output.
failed_list() { rm -f "$1/Testing/Temporary/LastTestsFailed.log"; }
failed_list build
start=$SECONDS
ctest --test-dir build --output-on-failure -j 2
normal=$?
echo "test.sh: normal suite exit code $normal after $((SECONDS - start)) s"

start=$SECONDS
fuzz=1
# Line tables only (-g1), as setup.sh's build: a crash's stack keeps file:line, the build is faster.
if cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
    -DCMAKE_CXX_COMPILER=clang++ -DDPC31_FUZZ=ON -DDPC31_WERROR=ON \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" \
    >/dev/null && ninja -C build-fuzz; then
  echo "test.sh: fuzz build took $((SECONDS - start)) s"
  start=$SECONDS
  failed_list build-fuzz
  ctest --test-dir build-fuzz --output-on-failure -j 2
  fuzz=$?
  echo "test.sh: fuzz runs exit code $fuzz after $((SECONDS - start)) s"
else
  echo "test.sh: the fuzz build failed"
fi

start=$SECONDS
asan=1
if cmake --preset asan && cmake --build --preset asan -j "$(nproc)"; then
  echo "test.sh: asan build took $((SECONDS - start)) s"
  start=$SECONDS
  failed_list build-asan
  ctest --preset asan
  asan=$?
  echo "test.sh: asan suite exit code $asan after $((SECONDS - start)) s"
else
  echo "test.sh: the asan build failed"
fi

start=$SECONDS
clang=1
if cmake --preset clang-release && cmake --build --preset clang-release -j "$(nproc)"; then
  echo "test.sh: clang-release build took $((SECONDS - start)) s"
  start=$SECONDS
  failed_list build-clang
  ctest --preset clang-release
  clang=$?
  echo "test.sh: clang-release suite exit code $clang after $((SECONDS - start)) s"
else
  echo "test.sh: the clang-release build failed"
fi

echo "test.sh: exit codes: normal $normal, fuzz $fuzz, asan $asan, clang-release $clang"
for d in build build-fuzz build-asan build-clang; do
  if [ -s "$d/Testing/Temporary/LastTestsFailed.log" ]; then
    echo "test.sh: failed in $d:"
    sed 's/^/  /' "$d/Testing/Temporary/LastTestsFailed.log"
    # The last lines of each failed test's output, from CTest's own log.
    python3 - "$d/Testing/Temporary/LastTest.log" "$d/Testing/Temporary/LastTestsFailed.log" <<'PY'
import sys
log = open(sys.argv[1], errors="replace").read().split("\n")
for entry in open(sys.argv[2]).read().split():
    name = entry.split(":", 1)[-1]
    starts = [i for i, l in enumerate(log) if l.endswith(" Test: " + name)]
    if not starts:
        continue
    block = []
    for l in log[starts[-1]:]:
        if l.startswith("<end of output>"):
            break
        block.append(l)
    print(f"test.sh: the end of {name}'s output:")
    for l in block[-25:]:
        print("    " + l)
PY
  fi
done

[ "$normal" -eq 0 ] && [ "$fuzz" -eq 0 ] && [ "$asan" -eq 0 ] && [ "$clang" -eq 0 ]
