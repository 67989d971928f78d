#!/bin/sh
# Lint rtl/dpc31_blocks.v with Verilator -Wall on every profile, plain and with each mutant.
# Usage: rtl/lint.sh   (from anywhere; exit 1 on the first warning or error)
set -eu
cd "$(dirname "$0")/.."
mutants="MUTANT_NEXT_DOUT_KEEPS_N MUTANT_ACK_NEIGHBOUR MUTANT_EOI_SHORT
MUTANT_CLEAR_IGNORED_IN_SYNC MUTANT_NO_C_SWAP MUTANT_ACK_BEATS_EVENT MUTANT_POLARITY
MUTANT_FREEZE_IGNORED MUTANT_NO_CONFLICT MUTANT_DIAG_FLAG_STICKY"
n=0
for p in 0 1 2; do
  for m in NONE $mutants; do
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
echo "lint clean: $n configurations (3 profiles x (plain + 10 mutants))"
