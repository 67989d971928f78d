#!/bin/sh
# CTest Cosim.shards_parallel_merge (docs/regression.md): a run split into 4 shards that GNU
# parallel runs, merged with `dpc31 cosim merge`, equals the same run unsharded: the JUnit file
# byte for byte (test counts, seeds, failures), the JSON summary except the wall-clock fields,
# and the exit code (the verdict). Once clean, once with a mutant that some seeds catch (shards
# numbered from 0 there, --shard-base 0, as a Kubernetes Indexed Job numbers them).
# Usage: cosim_shards.sh DPC31_CLI WORK_DIR
set -eu
cli=$1
work=$2
rm -rf "$work"
mkdir -p "$work"
cd "$work"

same_json() {  # the two summaries equal but for seconds and the rate
  python3 - "$1" "$2" <<'PY'
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:3])
for s in (a, b):
    for k in ("seconds", "lockstep_cycles_per_second"):
        s.pop(k)
if a != b:
    sys.exit(f"{sys.argv[1]} and {sys.argv[2]} differ")
PY
}

# check NAME WANT_EXIT SHARD_BASE ARGS...: 4 shards through parallel, the merge, the whole run.
check() {
  name=$1 want=$2 base=$3
  shift 3
  mkdir "$name"
  first=$base
  last=$((base + 3))
  # parallel's exit code is the number of jobs that failed: each divergent shard exits 1.
  rc=0
  parallel --halt never "$cli" cosim "$@" --keep-going --quiet --out "$name/out" \
    --shard-base "$base" --shard '{}/4' --junit "$name/shard{}.xml" '>' "$name/shard{}.json" \
    ::: $(seq "$first" "$last") || rc=$?
  echo "$name: parallel exit $rc"
  rc=0
  "$cli" cosim merge "$name"/shard*.json --junit "$name/merged.xml" > "$name/merged.json" || rc=$?
  [ "$rc" = "$want" ] || { echo "$name: merge exit $rc, want $want" >&2; exit 1; }
  rc=0
  "$cli" cosim "$@" --keep-going --quiet --out "$name/out" --junit "$name/whole.xml" \
    > "$name/whole.json" || rc=$?
  [ "$rc" = "$want" ] || { echo "$name: unsharded exit $rc, want $want" >&2; exit 1; }
  cmp "$name/merged.xml" "$name/whole.xml"
  same_json "$name/merged.json" "$name/whole.json"
  # The shards' own JUnit files add up to the whole (each seed in exactly one shard).
  n=$(cat "$name"/shard*.xml | grep -c '<testcase ')
  total=$(grep -o 'tests="[0-9]*"' "$name/whole.xml")
  [ "tests=\"$n\"" = "$total" ] || { echo "$name: shards hold $n test cases, $total" >&2; exit 1; }
  echo "$name: merge of 4 shards = unsharded run ($total, $(grep -o 'failures="[0-9]*"' \
    "$name/whole.xml"), exit $want)"
}

check clean 0 1 --profile dpc31 --seeds 40 --cycles 5000
check mutant 1 0 --profile dpc31 --mutant POLARITY --seeds 16 --cycles 1000
# A shard missing or given twice is bad input, not a verdict.
rc=0
"$cli" cosim merge clean/shard1.json clean/shard2.json clean/shard4.json 2> missing.err || rc=$?
[ "$rc" = 2 ] && grep -q 'shard 3/4 missing' missing.err
rc=0
"$cli" cosim merge clean/shard1.json clean/shard1.json 2> twice.err > /dev/null || rc=$?
[ "$rc" = 2 ] && grep -q 'given twice' twice.err
echo "merge refuses a missing and a doubled shard (exit 2)"
