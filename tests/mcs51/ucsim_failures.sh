#!/bin/sh
# Mcs51.UcsimCheckFailures: an s51 that fails (a signal, no trace, no end in time, not there) and
# a bad --limit are exit 2 with one line that says so, never "differs"; a coverage gap is exit 1
# beside "1 of 1 programs equal"; nothing is left behind:
# no script in TMPDIR, no s51 (or what it started) running; --help and the default limit.
# Usage: ucsim_failures.sh CHECK PROGRAM [LONG_PROGRAM]
set -u
check=$1
prog=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
mkdir "$dir/tmp"
printf '#!/bin/sh\nkill -SEGV $$\n' >"$dir/crash"
printf '#!/bin/sh\nexit 0\n' >"$dir/silent"
printf '#!/bin/sh\necho "no such core" >&2\nexit 3\n' >"$dir/refuses"
printf '#!/bin/sh\necho $$ >>"%s/pids"\nsleep 30 &\necho $! >>"%s/pids"\nwait\n' "$dir" "$dir" >"$dir/slow"
chmod +x "$dir/crash" "$dir/silent" "$dir/refuses" "$dir/slow"
fail=0
# WANT ARGS...: the check on two programs (a batch of two s51 runs) with ARGS.
expect() {
  want=$1
  shift
  TMPDIR=$dir/tmp "$check" "$@" "$prog" "$prog" >/dev/null 2>"$dir/err"
  rc=$?
  got=$(cat "$dir/err")
  [ $rc -eq 2 ] || { echo "$*: exit $rc, not 2"; fail=1; }
  [ "$got" = "$want" ] || { echo "$*: said '$got', not '$want'"; fail=1; }
  [ -z "$(ls -A "$dir/tmp")" ] || { echo "$*: left in TMPDIR: $(ls "$dir/tmp")"; fail=1; }
}
expect "$prog: s51 was ended by signal 11 (Segmentation fault)" --s51 "$dir/crash"
expect "$prog: s51 gave no trace (no 'Stop at' line)" --s51 "$dir/silent"
expect "$prog: s51 ended with exit code 3: no such core" --s51 "$dir/refuses"
expect "$prog: cannot start s51 $dir/none: No such file or directory" --s51 "$dir/none"
expect "$prog: s51 gave no end within 1 s: killed" --s51 "$dir/slow" --timeout 1
usage="(usage: mcs51_ucsim_check [--limit N] [--timeout S] [--s51 PATH] [--coverage] PROGRAM.ihx...)"
expect "mcs51_ucsim_check: --limit 'abc' must be a whole number 1..100000000 $usage" --limit abc
expect "mcs51_ucsim_check: --timeout '0' must be a whole number 1..100000000 $usage" --timeout 0
# --help is the usage on stdout, exit 0, as the CLI's; without --limit a program runs to its SJMP $
# or 20 000 steps (docs/cpu.md, "The ucsim cross-check"): the s35 audit found 3 000.
"$check" --help >"$dir/help.txt"
rc=$?
help=$(head -n 1 "$dir/help.txt")
[ $rc -eq 0 ] || { echo "--help: exit $rc, not 0"; fail=1; }
[ "($help)" = "$usage" ] || { echo "--help: $help"; fail=1; }
if [ $# -ge 3 ]; then  # a program longer than 3 000 steps (DO4 for the 80C32)
  long=$("$check" "$3" | head -n 1)
  [ "$long" = "$("$check" --limit 20000 "$3" | head -n 1)" ] &&
    [ "$long" != "$("$check" --limit 3000 "$3" | head -n 1)" ] || { echo "default limit: $long"; fail=1; }
fi
# --coverage on one program that is equal but runs a few opcodes: the program counts as equal,
# the gap is a verdict of its own (exit 1), not an unequal program.
out=$("$check" --coverage "$prog")
rc=$?
[ $rc -eq 1 ] || { echo "--coverage: exit $rc, not 1"; fail=1; }
printf '%s\n' "$out" | grep -qx "1 of 1 programs equal" || { echo "--coverage: $out"; fail=1; }
printf '%s\n' "$out" | tail -n 1 | grep -q "^coverage: opcodes no program ran: " ||
  { echo "--coverage, last line: $out"; fail=1; }
# Both slow runs (the one that timed out, the other of its batch) and their sleeps are gone.
[ "$(wc -l <"$dir/pids")" -eq 4 ] || { echo "the slow s51 did not start twice"; fail=1; }
for pid in $(cat "$dir/pids"); do
  n=0
  while [ -e "/proc/$pid" ] && [ "$(cut -d' ' -f3 "/proc/$pid/stat" 2>/dev/null)" != Z ] && [ $n -lt 50 ]; do
    sleep 0.1
    n=$((n + 1))
  done
  if [ $n -eq 50 ]; then
    echo "process $pid of the slow s51 still running"
    kill "$pid"
    fail=1
  fi
done
exit $fail
