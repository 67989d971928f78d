#!/bin/sh
# The emulator's dump and the Verilated RTL's own FST of the same stimulus compare equal in
# clock-sampled mode after name mapping; with a mutant the first divergence is the mutated signal
# at the cycle the lockstep found. Usage: wavediff_rtl.sh path/to/dpc31
set -eu
dpc31=$1
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
"$dpc31" cosim --seeds 1 --cycles 3000 --dump "$d/ok" --quiet > /dev/null
"$dpc31" wavediff "$d/ok/emu.vcd" "$d/ok/rtl_internal.fst" --clock clk --strip auto --ignore-missing > "$d/ok.txt"
grep -q "compared 31 signals: 0 differ" "$d/ok.txt"
# EOI one cycle short: the lockstep stops at the first divergence (exit 1).
if "$dpc31" cosim --mutant EOI_SHORT --seeds 1 --cycles 3000 --dump "$d/m" --quiet > "$d/m.json"; then exit 1; fi
cycle=$(grep '"cycle":' "$d/m.json" | head -1 | tr -dc 0-9)
if "$dpc31" wavediff "$d/m/emu.vcd" "$d/m/rtl.vcd" --clock blocks.clk > "$d/m.txt"; then exit 1; fi
grep -q "first divergence: blocks.x_int at cycle $cycle " "$d/m.txt"
echo "same without the mutant; with EOI_SHORT: blocks.x_int at cycle $cycle, as the lockstep found"
