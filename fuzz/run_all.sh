#!/usr/bin/env bash
# Runs every fuzz target one after the other (the machine has 2 shared cores), each for
# ${SECONDS_EACH:-600} s, on fuzz/corpus/<target> (grown, not committed) seeded from
# fuzz/seeds/<target> (committed; rebuild with fuzz/seed.sh). Builds all targets once
# (`cargo +nightly fuzz build -O`), then runs the binaries directly so that edits to the crate
# during a long session do not rebuild between targets. Logs go to fuzz/logs/<target>.log; the
# last line of each is libFuzzer's "Done N runs in S second(s)". Run from the repository root.
set -uo pipefail
cd fuzz
mkdir -p logs
target_dir=${CARGO_TARGET_DIR:-target}
[ -n "${NO_BUILD:-}" ] || cargo +nightly fuzz build -O || exit 1
for t in ${TARGETS:-ply obj stl xyz adjacency svg}; do
  mkdir -p corpus/$t
  echo "$(date -u +%FT%TZ) start $t" >> logs/summary.txt
  "$target_dir"/x86_64-unknown-linux-gnu/release/$t corpus/$t seeds/$t \
    -max_total_time=${SECONDS_EACH:-600} -max_len=8192 -rss_limit_mb=2048 -timeout=10 \
    -artifact_prefix=artifacts/$t/ > logs/$t.log 2>&1
  echo "$(date -u +%FT%TZ) end $t rc=$? $(grep -E '^Done [0-9]+ runs' logs/$t.log)" >> logs/summary.txt
done
