#!/usr/bin/env bash
# Generates ShadyLoc's larger simulated evaluation set (config/sim_eval.ini,
# docs/sim.md "The evaluation set"), deterministically: the whole 300 m route
# (tree-lined avenue, street of buildings, open stretch) driven under six
# lighting conditions (low morning sun ahead-left, high noon sun dappled
# through the canopy, afternoon sun from the right, low evening sun from
# behind-right, hazy sun, overcast) plus one noon drive 3.5 m to the side in
# the other lane; each from route s = 0 to its first frame at or past
# s = 301 m (1 m past the route's end, so every ground-truth path is at
# least 300 m), 512x384 stereo at 10 Hz, with ground truth. 2667 stereo
# frames, ~2 GB, ~8 min of CPU time. Not run in CI.
#
#   scripts/make-eval-dataset.sh [OUTDIR] [extra `shadyloc sim` options]
#
# OUTDIR defaults to rawlogs/eval (git-ignored). Writes OUTDIR/<run>.rawlog
# and OUTDIR/<run>.tum per traversal, then OUTDIR/SHA256SUMS of them and
# OUTDIR/lengths.txt (frames and ground-truth path length per run). The
# conditions are frozen: tests/golden/sim_eval_frames.txt, checked by the
# test SimEvalFrozen.* (config/sim_eval.ini says how to change them on purpose).
# Needs a built build/shadyloc (scripts/setup.sh).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="${SHADYLOC_APP:-$here/build/shadyloc}"
out="${1:-$here/rawlogs/eval}"
shift || true
if [ ! -x "$app" ]; then
  echo "make-eval-dataset: '$app' not found: build first (scripts/setup.sh)" >&2
  exit 1
fi
start=$(date +%s)
echo "make-eval-dataset: rendering config/sim_eval.ini into $out (progress below; 2667 frames)"
# Without -q the simulator prints its plan (frames and route stretch of each
# run), then each run's progress every 2 s.
# (The options dump it prints first is left out: config/sim_eval.ini is it.)
if ! "$app" sim -c "$here/config/sim_eval.ini" -o "$out" "$@" |
  { grep --line-buffered -v -E '^(\[sim|\[traversal|; |[a-zA-Z_]+ = |$|Simulator options)' || true; }; then
  echo "make-eval-dataset: shadyloc sim failed (nothing of this run was kept)" >&2
  exit 1
fi
cd "$out"
sha256sum -- *.rawlog *.tum > SHA256SUMS.tmp && mv SHA256SUMS.tmp SHA256SUMS
# Ground-truth path length of each run (sum of the left camera's steps).
{
  printf "%-24s %7s %12s\n" run frames gt_length_m
  for tum in *.tum; do
    awk -v r="${tum%.tum}" '!/^#/ && NF >= 8 {
        if (n) len += sqrt(($2 - x) ^ 2 + ($3 - y) ^ 2 + ($4 - z) ^ 2)
        x = $2; y = $3; z = $4; n++ }
      END { printf "%-24s %7d %12.1f\n", r, n, len }' "$tum"
  done
} > lengths.txt.tmp && mv lengths.txt.tmp lengths.txt
cat lengths.txt
echo "make-eval-dataset: $(ls -- *.rawlog | wc -l) runs in $out ($(( $(date +%s) - start )) s, $(du -sh . | cut -f1))"
