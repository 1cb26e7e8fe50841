#!/usr/bin/env bash
# Runs every fuzz target one after the other (the machine has 2 shared cores), each for
# ${SECONDS_EACH:-600} s, on fuzz/corpus/<target> (grown, not committed) seeded from
# fuzz/seeds/<target> (committed; rebuild with fuzz/seed.sh). Logs go to fuzz/logs/<target>.log;
# the last line of each is libFuzzer's "Done N runs in S second(s)". Run from the repository root.
set -uo pipefail
cd fuzz
mkdir -p logs
for t in ${TARGETS:-ply obj stl xyz adjacency}; do
  mkdir -p corpus/$t
  echo "$(date -u +%FT%TZ) start $t" >> logs/summary.txt
  cargo +nightly fuzz run -O "$t" corpus/$t seeds/$t -- \
    -max_total_time=${SECONDS_EACH:-600} -max_len=8192 -rss_limit_mb=2048 -timeout=10 \
    > logs/$t.log 2>&1
  echo "$(date -u +%FT%TZ) end $t rc=$? $(grep -E '^Done [0-9]+ runs' logs/$t.log)" >> logs/summary.txt
done
