#!/usr/bin/env bash
# The AMR render row (3) against OSPRay on every AMRClaw frame in the data
# directory and three views each, so the reported ratio is the worst case,
# not the frame and view the code was tuned on; then the same frames
# rewritten as an AMReX plotfile and a FLASH file by tools/amr_formats.py
# (generated under out/amr-formats the first time; voxless reads them with
# --amr, OSPRay gets the same boxes or blocks). Row 3's other peers (VTK,
# yt) run in the harness's main table. Usage (from the
# repository root, with the peers' venv as in README.md):
#   PY=../peers-venv/bin/python bash benchmarks/peers/amr_sweep.sh [--reps N] [--threads T]
set -eu
PY=${PY:-python3}
HERE=$(cd "$(dirname "$0")" && pwd)
for format in amrclaw amrex flash; do
  for frame in 2 3; do
    for view in 0 1 2; do
      echo "## $format (AMRClaw frame $frame), view $view"
      PEERS_AMR_FORMAT=$format PEERS_AMR_FRAME=$frame PEERS_AMR_VIEW=$view \
        "$PY" "$HERE/run.py" --rows 3 --python "$PY" --peers "OSPRay amr" "$@"
    done
  done
done
