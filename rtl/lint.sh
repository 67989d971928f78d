#!/bin/sh
# Lint rtl/dpc31_blocks.v with Verilator -Wall on every profile, plain and with the mutants
# (`define MUTANTS: every mutant behind the mutant_sel input).
# Usage: rtl/lint.sh   (from anywhere; exit 1 on the first warning or error)
set -eu
cd "$(dirname "$0")/.."
n=0
for p in 0 1 2; do
  for m in NONE MUTANTS; do
    def=""
    [ "$m" = NONE ] || def="-D$m"
    # shellcheck disable=SC2086
    if ! verilator --lint-only -Wall -Irtl rtl/dpc31_blocks.v --top-module dpc31_blocks \
        -GPROFILE=$p $def; then
      echo "lint FAILED: PROFILE=$p $m" >&2
      exit 1
    fi
    n=$((n + 1))
  done
done
echo "lint clean: $n configurations (3 profiles x (plain + mutants))"
