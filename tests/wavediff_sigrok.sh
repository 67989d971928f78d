#!/bin/sh
# A sigrok-cli export of our VCD (as from a logic-analyser workflow) is accepted and compared.
# Usage: wavediff_sigrok.sh path/to/dpc31 source-dir
set -eu
dpc31=$1
src=$2
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
"$dpc31" run "$src/traces/startup_dpc31_12m.scn" --quiet --vcd "$d/run.vcd" --signals 'pins.rxd,pins.txd' --flat \
  --timescale 10ns
sigrok-cli -I vcd -i "$d/run.vcd" -O vcd -o "$d/sigrok.vcd" > /dev/null
"$dpc31" wavediff "$d/run.vcd" "$d/sigrok.vcd" --strip auto > "$d/out.txt"
grep -q "compared 2 signals: 0 differ" "$d/out.txt"
cat "$d/out.txt"
