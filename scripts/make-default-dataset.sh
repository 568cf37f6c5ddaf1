#!/usr/bin/env bash
# Generates ShadyLoc's default dataset with the simulator, deterministically
# (every pixel follows from the seeds in config/sim.ini): 4 traversals of the
# same 90 m of road (route s = 80 to 170 m: the last 30 m of the tree-lined
# avenue, then 60 m of the street of buildings) under morning low sun, noon,
# warm evening and overcast light, each starting at s = 80 m and ending at
# its first frame at or past s = 170 m (105-124 stereo frames at 512x384,
# 10 Hz; 455 in all): ~85 s of CPU time, ~345 MB.
# See rawlogs/README.md.
#
#   scripts/make-default-dataset.sh [OUTDIR] [extra `shadyloc sim` options]
#
# OUTDIR defaults to rawlogs/generated (git-ignored). Needs a built
# build/shadyloc (scripts/setup.sh).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="${SHADYLOC_APP:-$here/build/shadyloc}"
out="${1:-$here/rawlogs/generated}"
shift || true
if [ ! -x "$app" ]; then
  echo "make-default-dataset: '$app' not found: build first (scripts/setup.sh)" >&2
  exit 1
fi
start=$(date +%s)
"$app" sim -c "$here/config/sim.ini" -o "$out" "$@"
echo "make-default-dataset: $(ls "$out"/*.rawlog | wc -l) rawlogs in $out ($(( $(date +%s) - start )) s, $(du -sh "$out" | cut -f1))"
