#!/bin/sh
# dpc31_fuzz_make_seeds's bad input as every program's (docs/bad-input.md): one line on stderr,
# exit 2, nothing made for it; --help prints the usage (exit 0) and makes no directory "--help".
# usage: make_seeds_bad_input.sh MAKE_SEEDS
set -u
make_seeds=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT INT TERM
cd "$work" || exit 1
failed=0
# expect RC LINES ARGS...: exit RC, LINES lines on stderr, nothing left in $work but the file f.
expect() {
  rc=$1 lines=$2
  shift 2
  "$make_seeds" "$@" >/dev/null 2>"$work.err"
  got=$?
  n=$(wc -l <"$work.err")
  left=$(ls -A | grep -v '^f$')
  if [ "$got" -ne "$rc" ] || [ "$n" -ne "$lines" ] || [ -n "$left" ]; then
    echo "make_seeds $*: exit $got ($rc expected), $n lines on stderr ($lines expected), left: $left"
    cat "$work.err"
    failed=1
  fi
  # Each case on its own: what one left is not counted against the next.
  find . -mindepth 1 -maxdepth 1 ! -name f -exec rm -rf {} +
}
: >f
expect 0 0 --help
expect 2 1
expect 2 1 --bogus
expect 2 1 a b
expect 2 1 no/such/dir
expect 2 1 f
expect 2 1 f/x
rm -f "$work.err"
[ "$failed" -eq 0 ] && echo "every bad input refused with one line"
exit "$failed"
