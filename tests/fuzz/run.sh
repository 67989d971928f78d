#!/bin/sh
# Runs one fuzz target (docs/robustness.md): tests/fuzz/run.sh TARGET SECONDS BUILD_DIR WORK_DIR
# New inputs go to WORK_DIR/TARGET/corpus, findings to WORK_DIR/TARGET/, the log (with
# libFuzzer's final stats) to WORK_DIR/TARGET/fuzz.log. Exit code: libFuzzer's.
set -eu
target=$1 seconds=$2 build=$3 work=$4
src=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$work/$target/corpus"
cd "$work/$target"
# fstapi leaks what it allocated when it gives up (its exit() path, see docs/robustness.md).
export LSAN_OPTIONS="suppressions=$src/lsan_fstapi.supp:print_suppressions=0"
# fstapi mallocs sizes read from the file and handles a NULL result (as glibc gives for absurd
# sizes); ASan would abort instead. Only for the FST target: our own code gets no such leeway.
# fstapi also has memory errors of its own on corrupt blocks that no check of ours can rule out
# (docs/robustness.md): the FST target runs in fork mode, which records each crash and goes on.
extra=
if [ "$target" = fst_reader ]; then
  export ASAN_OPTIONS=allocator_may_return_null=1
  extra="-fork=1 -ignore_crashes=1"
fi
exec nice "$build/bin/fuzz_$target" corpus "$src/corpus/$target" \
  -max_total_time="$seconds" -timeout=10 -timeout_exitcode=70 -rss_limit_mb=2048 -print_final_stats=1 \
  -artifact_prefix="$work/$target/" $extra >fuzz.log 2>&1
