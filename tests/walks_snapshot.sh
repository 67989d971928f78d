#!/usr/bin/env bash
# Byte-for-byte record of what every scenario and golden trace gives (issue 15's refactor check):
#   tests/walks_snapshot.sh DPC31_BINARY OUT_DIR
# For each traces/*.scn: the state walk (stdout, stderr, exit code), the JSON summary, the
# recorded trace, the VCD and the pcapng; for each traces/*.trace: the replay's output. Compare
# two such directories with `diff -r`.
set -uo pipefail
bin=$(realpath "$1")
out=$2
src=$(cd "$(dirname "$0")/.." && pwd)
out=$(mkdir -p "$out" && cd "$out" && pwd)
cd "$src/traces"  # relative names: the output does not depend on where the tree is
for scn in *.scn; do
  n=${scn%.scn}
  "$bin" run "$scn" --json "$out/$n.json" --record "$out/$n.rec.trace" --vcd "$out/$n.vcd" \
    --pcap "$out/$n.pcapng" >"$out/$n.walk" 2>"$out/$n.err"
  echo "exit $?" >>"$out/$n.walk"
  "$bin" run "$scn" --engine per-cycle >"$out/$n.percycle.walk" 2>&1
  echo "exit $?" >>"$out/$n.percycle.walk"
done
for tr in *.trace; do
  n=${tr%.trace}
  "$bin" replay "$tr" >"$out/$n.replay" 2>&1
  echo "exit $?" >>"$out/$n.replay"
done
# The JSON summaries and VCD headers name the file paths and dates: keep only what the chip did.
sed -i -E 's/^\$date.*$/$date (removed)/' "$out"/*.vcd 2>/dev/null || true
