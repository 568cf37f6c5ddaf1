#!/usr/bin/env bash
# Stereo VO on both channels of every simulated traversal in a folder, errors
# against the ground truth beside each rawlog, one table.
#   bash scripts/vo-table.sh DATA_DIR OUT_DIR [CONFIG]
# DATA_DIR holds <traversal>.rawlog + <traversal>.tum (shadyloc sim output);
# OUT_DIR gets <traversal>_<channel>.{tum,csv,err} and vo_summary.txt.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="${SHADYLOC_APP:-$here/build/shadyloc}"
data="${1:?usage: vo-table.sh DATA_DIR OUT_DIR [CONFIG]}"
out="${2:?usage: vo-table.sh DATA_DIR OUT_DIR [CONFIG]}"
cfg="${3:-$here/config/vo_sim.ini}"
[ -x "$app" ] || { echo "vo-table: $app not built: run scripts/setup.sh first" >&2; exit 1; }
ls "$data"/*.rawlog >/dev/null 2>&1 || { echo "vo-table: no .rawlog in $data" >&2; exit 1; }
mkdir -p "$out"
summary="$out/vo_summary.txt"
tmp="$summary.tmp"
printf "%-18s %-10s %9s %10s %14s %10s %10s\n" traversal channel length_m "trans_%" "rot_deg_per_m" "ATE_m" untracked > "$tmp"
for rawlog in "$data"/*.rawlog; do
  trav="$(basename "$rawlog" .rawlog)"
  [ -f "$data/$trav.tum" ] || { echo "vo-table: no ground truth $data/$trav.tum" >&2; exit 1; }
  for ch in mono invariant; do
    "$app" vo -q -i "$rawlog" --channel "$ch" -c "$cfg" -o "$out/${trav}_$ch.tum" --stats "$out/${trav}_$ch.csv"
    "$app" traj-error --gt "$data/$trav.tum" --est "$out/${trav}_$ch.tum" > "$out/${trav}_$ch.err"
    untracked=$(awk -F, 'NR > 1 && $8 != "ok" && $8 != "first"' "$out/${trav}_$ch.csv" | wc -l)
    awk -v t="$trav" -v c="$ch" -v u="$untracked" '
      /^path length:/ {len=$3}
      /^ATE RMSE:/ {ate=$3}
      /^KITTI-style average:/ {tr=$4; rot=$7}
      END {printf "%-18s %-10s %9.1f %10s %14s %10s %10s\n", t, c, len, tr, rot, ate, u}' "$out/${trav}_$ch.err" >> "$tmp"
  done
done
mv "$tmp" "$summary"
cat "$summary"
