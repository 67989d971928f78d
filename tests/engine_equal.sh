#!/bin/sh
# The event engine against the per-cycle reference engine (docs/engine.md): one scenario run both
# ways with the full waveform (pins, bus, state, blocks); `dpc31 wavediff` must find them
# identical (exit 0). Then both ways with nothing watching the bus, where the event engine takes
# its plain accesses and block transfers (docs/engine.md, "Plain accesses"): the state walks,
# every line with its cycle, must be identical. Usage: engine_equal.sh path/to/dpc31 SCENARIO
set -eu
dpc31=$1
scn=$2
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
"$dpc31" run --quiet --engine event --vcd "$d/event.vcd" "$scn"
"$dpc31" run --quiet --engine per-cycle --vcd "$d/per_cycle.vcd" "$scn"
"$dpc31" wavediff "$d/event.vcd" "$d/per_cycle.vcd"
"$dpc31" run --engine event "$scn" >"$d/event.walk"
"$dpc31" run --engine per-cycle "$scn" >"$d/per_cycle.walk"
diff "$d/event.walk" "$d/per_cycle.walk"
