#!/usr/bin/env bash
# Runs scansurf's whole test suite: the library's unit tests and the integration tests (one test
# binary, tests/it), built with the `fasttest` profile (optimized, quick to rebuild; Cargo.toml).
# Creates the Python venv with the independent CAD checker (OpenCASCADE via cadquery-ocp,
# ../shared/tools/requirements.txt) on first use, so the tests that read our STEP/IGES back
# through OpenCASCADE can run.
#
#   bash scripts/test.sh                 everything (what CI and the README run)
#   bash scripts/test.sh --quick         everything but the long end-to-end fits (tests named slow_*)
#   bash scripts/test.sh cli_fit::       any other arguments go to `cargo test` (here: a filter)
#
# docs/DEVELOPING.md explains the tiers and how to run one module's tests.
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
args=()
for a in "$@"; do
  case "$a" in
    --quick) quick=1 ;;
    *) args+=("$a") ;;
  esac
done
req=../shared/tools/requirements.txt
if [ -f "$req" ]; then
  if [ ! -x .venv-check/bin/python ]; then
    python3 -m venv .venv-check
  fi
  stamp=.venv-check/.installed
  if [ ! -f "$stamp" ] || ! cmp -s "$req" "$stamp"; then
    .venv-check/bin/pip install --quiet --disable-pip-version-check -r "$req"
    cp "$req" "$stamp"
  fi
else
  echo "note: $req not found; CAD round-trip tests will fail without the checker" >&2
fi
if [ "$quick" = 1 ]; then
  # The skip filter goes to the test harness: after the caller's own `--` if there is one.
  has_sep=0
  for a in "${args[@]+"${args[@]}"}"; do [ "$a" = "--" ] && has_sep=1; done
  if [ "$has_sep" = 1 ]; then
    args+=(--skip slow_)
  else
    args+=(-- --skip slow_)
  fi
fi
# --tests: the library's and the binary's unit tests and tests/it (examples and benches are
# compiled by clippy --all-targets in CI, not linked here).
cargo test --profile fasttest --tests "${args[@]+"${args[@]}"}"
if [ "$quick" = 0 ] && [ "${#args[@]}" = 0 ]; then
  # The doc comments' code blocks (text today; a Rust block would be compiled and run here).
  cargo test --profile fasttest --doc
fi
