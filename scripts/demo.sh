#!/usr/bin/env bash
# ShadyLoc's main job on the built-in default data (run scripts/setup.sh first):
#  1. the default dataset: 4 simulated traversals of one road under different
#     light (generated deterministically on first use, ~30 s);
#  2. observation filters: monochrome + invariant channels of one traversal,
#     checked with stock MRPT tools through the plugin;
#  3. stereo VO on both channels of every traversal, errors against ground truth;
#  4. an offscreen picture of the trajectories.
# Everything goes to build/demo/.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="$here/build/shadyloc"
plugin="$here/build/libshadyloc_mrpt_plugin.so"
data="$here/rawlogs/generated"
out="$here/build/demo"
vo_cfg="$here/config/vo_sim.ini"
[ -f "$vo_cfg" ] || vo_cfg="$here/config/vo.ini"
[ -x "$app" ] || { echo "demo: $app not built: run scripts/setup.sh first" >&2; exit 1; }
mkdir -p "$out"

echo "== 1. default dataset ($data)"
if ! ls "$data"/*.rawlog >/dev/null 2>&1; then
  bash "$here/scripts/make-default-dataset.sh" "$data"
else
  echo "already there: $(ls "$data"/*.rawlog | wc -l) traversals"
fi

echo
echo "== 2. shadyloc filter: monochrome + invariant channels of 'noon'"
"$app" filter -q -i "$data/noon.rawlog" -o "$out/noon_filtered.rawlog" -c "$here/config/filters_sim.ini"
if command -v rawlog-edit >/dev/null; then
  rawlog-edit -p "$plugin" -i "$out/noon_filtered.rawlog" --info | grep -E "number of objects|Sensor \(" || true
fi

echo
echo "== 3. stereo VO, both channels, every traversal (config: ${vo_cfg#$here/})"
bash "$here/scripts/vo-table.sh" "$data" "$out" "$vo_cfg"

echo
echo "== 4. trajectories, rendered offscreen"
"$app" render --title "noon: ground truth vs stereo VO (SE(3)-aligned)" \
  -t "$data/noon.tum:ground truth" -t "$out/noon_mono.tum:VO mono" -t "$out/noon_invariant.tum:VO invariant" \
  -o "$out/noon_trajectories.png" --align

echo
echo "Done. Results in $out/"
echo "Open the filtered rawlog: RawLogViewer -l $plugin $out/noon_filtered.rawlog"
