#!/usr/bin/env bash
# Runs scansurf's whole test suite. Creates the Python venv with the independent CAD checker
# (OpenCASCADE via cadquery-ocp, ../shared/tools/requirements.txt) on first use, so the tests
# that read our STEP/IGES back through OpenCASCADE can run.
set -euo pipefail
cd "$(dirname "$0")/.."
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
cargo test --release "$@"
