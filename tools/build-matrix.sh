#!/usr/bin/env bash
# Every CMake build type with both compilers (docs/install.md, "Build types and compilers"):
# configures each into build-matrix/<compiler>-<type>/ with -Werror on (DPC31_WERROR, as our
# development builds), builds it, runs the whole suite, and prints one line per configuration.
#   tools/build-matrix.sh                       # g++ and clang++ x Debug Release RelWithDebInfo MinSizeRel
#   tools/build-matrix.sh clang++:Debug g++:MinSizeRel   # chosen configurations only
# Exit 0 only if every configuration built and passed. Logs: build-matrix/<config>.log.
set -uo pipefail
cd "$(dirname "$0")/.."

configs=("$@")
if ((${#configs[@]} == 0)); then
  for cxx in g++ clang++; do
    for type in Debug Release RelWithDebInfo MinSizeRel; do configs+=("$cxx:$type"); done
  done
fi

mkdir -p build-matrix
summary=()
failed=0
for config in "${configs[@]}"; do
  cxx=${config%%:*}
  type=${config#*:}
  case $cxx in
    g++) cc=gcc ;;
    clang++) cc=clang ;;
    *) echo "build-matrix: unknown compiler '$cxx' (g++ or clang++)" >&2; exit 2 ;;
  esac
  case $type in
    Debug | Release | RelWithDebInfo | MinSizeRel) ;;
    *) echo "build-matrix: unknown build type '$type'" >&2; exit 2 ;;
  esac
  dir=build-matrix/$cc-$type
  log=build-matrix/$cc-$type.log
  start=$SECONDS
  if cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE="$type" -DCMAKE_C_COMPILER="$cc" \
      -DCMAKE_CXX_COMPILER="$cxx" -DDPC31_WERROR=ON >"$log" 2>&1 &&
    cmake --build "$dir" -j "$(nproc)" >>"$log" 2>&1; then
    built=$((SECONDS - start))
    warnings=$(grep -c 'warning:' "$log")
    start=$SECONDS
    ctest --test-dir "$dir" -j "$(nproc)" --output-on-failure >>"$log" 2>&1
    rc=$?
    result=$(grep -E '^[0-9]+% tests passed' "$log" | tail -n 1)
    line="$cxx $type: built in ${built} s, $warnings warnings; $result in $((SECONDS - start)) s"
    ((rc == 0)) || failed=1
  else
    line="$cxx $type: BUILD FAILED after $((SECONDS - start)) s (see $log)"
    failed=1
  fi
  echo "build-matrix: $line"
  summary+=("$line")
done
printf 'build-matrix: %s\n' "${summary[@]}"
exit $failed
