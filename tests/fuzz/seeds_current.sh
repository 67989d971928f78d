#!/bin/sh
# The generated seeds as the current writers make them (make_seeds.cpp) against the committed
# corpus: every file it writes must be there, byte for byte (docs/robustness.md, "Seeds").
# usage: seeds_current.sh MAKE_SEEDS CORPUS_DIR
set -eu
make_seeds=$1
corpus=$2
fresh=$(mktemp -d)
trap 'rm -rf "$fresh"' EXIT INT TERM
"$make_seeds" "$fresh"
stale=0
for f in $(cd "$fresh" && find . -type f | sort); do
  if ! cmp -s "$fresh/$f" "$corpus/$f"; then
    echo "stale seed: tests/fuzz/corpus/${f#./} differs from what make_seeds writes now"
    stale=$((stale + 1))
  fi
done
if [ "$stale" -ne 0 ]; then
  echo "$stale stale seeds: run $make_seeds $corpus and commit them"
  exit 1
fi
echo "every generated seed is current ($(cd "$fresh" && find . -type f | wc -l) files)"
