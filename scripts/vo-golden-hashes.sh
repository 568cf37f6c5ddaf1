#!/usr/bin/env bash
# SHA-256 of the stereo VO's TUM trajectories on the default dataset (4
# traversals x 2 channels, config/vo_sim.ini), and of the dataset's rawlogs,
# in `sha256sum` format. tests/golden/vo_default_hashes.txt is this script's
# output; the test VoGolden.DefaultDatasetTrajectoriesMatchCommittedHashes
# runs it and compares.
#   bash scripts/vo-golden-hashes.sh WORK_DIR [DATA_DIR]
# DATA_DIR: an existing default dataset (scripts/make-default-dataset.sh);
# without it the dataset is generated into WORK_DIR/data (once: reused while
# WORK_DIR/data/.complete exists). Trajectories go to WORK_DIR/vo.
# Regenerate the committed file (after a change that is meant to alter the VO):
#   bash scripts/vo-golden-hashes.sh build/golden > tests/golden/vo_default_hashes.txt
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="${SHADYLOC_APP:-$here/build/shadyloc}"
work="${1:?usage: vo-golden-hashes.sh WORK_DIR [DATA_DIR]}"
data="${2:-}"
[ -x "$app" ] || { echo "vo-golden-hashes: '$app' not built" >&2; exit 1; }
mkdir -p "$work"
if [ -z "$data" ]; then
  data="$work/data"
  if [ ! -f "$data/.complete" ]; then
    rm -rf "$data"
    SHADYLOC_APP="$app" bash "$here/scripts/make-default-dataset.sh" "$data" >&2
    touch "$data/.complete"
  fi
fi
traversals="evening_warm morning_low_sun noon overcast"
for t in $traversals; do
  [ -f "$data/$t.rawlog" ] || { echo "vo-golden-hashes: $data/$t.rawlog missing" >&2; exit 1; }
done
rm -rf "$work/vo"
mkdir -p "$work/vo"
for t in $traversals; do
  for ch in mono invariant; do
    "$app" vo -q -i "$data/$t.rawlog" --channel "$ch" -c "$here/config/vo_sim.ini" -o "$work/vo/${t}_$ch.tum" >&2
  done
done
echo "# Stereo VO trajectories on the default dataset, made by"
echo "#   bash scripts/vo-golden-hashes.sh WORK_DIR"
echo "# = scripts/make-default-dataset.sh (shadyloc sim -c config/sim.ini: s = 80 to 170 m), then for"
echo "# each traversal and channel: shadyloc vo -q -i T.rawlog --channel mono|invariant -c config/vo_sim.ini -o T_channel.tum"
echo "# The rawlogs' hashes come first: if they differ the simulator changed, not the VO."
(cd "$data" && for t in $traversals; do sha256sum "$t.rawlog" | sed 's|  |  data/|'; done)
(cd "$work/vo" && for t in $traversals; do for ch in mono invariant; do sha256sum "${t}_$ch.tum" | sed 's|  |  vo/|'; done; done)
