#!/usr/bin/env bash
# ShadyLoc's main job on the built-in default data (run scripts/setup.sh first):
#  1. the default dataset: 4 simulated traversals of one road under different
#     light, one common 90 m stretch (generated deterministically on first
#     use, ~85 s of CPU time);
#  2. observation filters: monochrome + invariant channels of one traversal,
#     checked with stock MRPT tools through the plugin;
#  3. stereo VO on both channels of every traversal, errors against ground truth;
#  4. the dual-channel keyframe map of one traversal (shadyloc survey), its
#     summary and its chain's error against ground truth (shadyloc map-info);
#  5. offscreen pictures of the trajectories and of the map (shadyloc render);
#  6. the leave-one-out evaluation (shadyloc eval): every traversal localised
#     against the map of every other, baseline (mono) alone and combined, against
#     ground truth: the paper's Table I, Figures 7-9 (build/demo/eval/figures/);
#  7. one localised pair rendered offscreen, coloured by localiser;
#  8. the same pair as an animated GIF: each channel's live image with its
#     matches against the map above the top-down view (docs/figures.md).
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
echo "== 4. keyframe map of 'noon' (shadyloc survey: mono VO chain, both channels' landmarks) and its summary"
"$app" survey -q -i "$data/noon.rawlog" -o "$out/noon.kfmap" -c "$vo_cfg" --gt "$data/noon.tum" | tail -n 1
"$app" map-info "$out/noon.kfmap"

echo
echo "== 5. trajectories and the map, rendered offscreen"
"$app" render --title "noon: ground truth vs stereo VO (SE(3)-aligned)" \
  -t "$data/noon.tum:ground truth" -t "$out/noon_mono.tum:VO mono" -t "$out/noon_invariant.tum:VO invariant" \
  -o "$out/noon_trajectories.png" --align
"$app" render --title "noon: keyframe map (shadyloc survey), ground truth over it" \
  -m "$out/noon.kfmap:noon" -t "$data/noon.tum:ground truth" --align --landmarks \
  --width 1000 --height 600 -o "$out/noon_map.png"

echo
echo "== 6. leave-one-out evaluation (shadyloc eval): every traversal against the map of every other,"
echo "      the baseline (mono) alone, the combined system (mono + invariant) and the budget-matched control"
echo "      (mono with both channels' feature budget, config/control_budget.ini), against ground truth"
loc_cfg="$here/config/localise_sim.ini"
runs="$out/runs.txt"
{
  echo "# the default dataset's traversals: name rawlog ground-truth (docs/evaluation.md)"
  for r in "$data"/*.rawlog; do
    n="$(basename "$r" .rawlog)"
    echo "$n $r $data/$n.tum"
  done
} > "$runs"
"$app" eval --runs "$runs" -o "$out/eval" -c "$vo_cfg" -c "$loc_cfg" --control "$here/config/control_budget.ini"

echo
echo "== 7. one pair of the evaluation rendered offscreen: 'overcast' against the 'noon' map, coloured by localiser"
"$app" render --title "overcast live run on the noon map, by localiser" \
  -m "$out/eval/jobs/map_noon/map.kfmap:noon map" --localised "$out/eval/pairs/overcast__noon__combined:overcast" \
  --gt "$data/overcast.tum" --width 1000 --height 600 -o "$out/overcast_on_noon.png"

echo
echo "== 8. the same pair as the localiser sees it, an animated GIF (shadyloc localise --gif): every third frame,"
echo "      each channel's live image with its matches against the map, above the top-down view"
"$app" localise -q -m "$out/noon.kfmap" -i "$data/overcast.rawlog" --gt "$data/overcast.tum" -c "$vo_cfg" -c "$loc_cfg" \
  -o "$out/overcast_on_noon" --gif "$out/overcast_on_noon.gif" --gif-every 3 --gif-fps 3.3 --view 42 --view-images | tail -n 1

echo
echo "Done. Results in $out/ (Table I: $out/eval/table1.md, figures: $out/eval/figures/)"
echo "Open the filtered rawlog: RawLogViewer -l $plugin $out/noon_filtered.rawlog"
