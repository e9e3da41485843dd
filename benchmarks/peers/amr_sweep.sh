#!/usr/bin/env bash
# The AMR render row (3) against OSPRay on every AMRClaw frame in the data
# directory and three views each, so the reported ratio is the worst case,
# not the frame and view the code was tuned on. Usage (from the repository
# root, with the peers' venv as in README.md):
#   PY=../peers-venv/bin/python bash benchmarks/peers/amr_sweep.sh [--reps N] [--threads T]
set -eu
PY=${PY:-python3}
HERE=$(cd "$(dirname "$0")" && pwd)
for frame in 2 3; do
  for view in 0 1 2; do
    echo "## AMRClaw frame $frame, view $view"
    PEERS_AMR_FRAME=$frame PEERS_AMR_VIEW=$view "$PY" "$HERE/run.py" --rows 3 --python "$PY" "$@"
  done
done
