#!/usr/bin/env bash
# Maps of several experiences in time order (docs/map.md, "Experiences"):
# the runs of EVAL_DIR in the order given, each localised by the combined
# system against the map of the runs before it, two ways:
#   all:   every run before appended as an experience (`survey --append`);
#   learn: the map grown only where a run went blind (`localise --learn`).
# Prints a markdown table per step: true coverage (in-map frames), false
# fixes, map size and keyframes, and frames per second of the live run.
#
#   scripts/experiences-in-time-order.sh EVAL_DIR OUTDIR [RUN...]
#
# RUN... defaults to the 301 m set in the order of a day and then the other
# days: morning_low_sun_left noon_dappled afternoon_side_sun
# evening_low_sun_right hazy_sun overcast noon_other_lane. What OUTDIR
# holds already is reused. About 30 min on 2 cores for the seven runs.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="${SHADYLOC_APP:-$here/build/shadyloc}"
eval_dir="${1:?usage: experiences-in-time-order.sh EVAL_DIR OUTDIR [RUN...]}"
out="${2:?usage: experiences-in-time-order.sh EVAL_DIR OUTDIR [RUN...]}"
shift 2
runs=("$@")
[ ${#runs[@]} -gt 0 ] || runs=(morning_low_sun_left noon_dappled afternoon_side_sun evening_low_sun_right hazy_sun overcast noon_other_lane)
[ ${#runs[@]} -ge 2 ] || { echo "experiences-in-time-order: two runs at least" >&2; exit 1; }
[ -x "$app" ] || { echo "experiences-in-time-order: '$app' not found: build first" >&2; exit 1; }
for r in "${runs[@]}"; do
  [ -f "$eval_dir/$r.rawlog" ] && [ -f "$eval_dir/$r.tum" ] ||
    { echo "experiences-in-time-order: $eval_dir/$r.rawlog or .tum missing" >&2; exit 1; }
done
mkdir -p "$out"
cfg=(-c "$here/config/vo_sim.ini" -c "$here/config/localise_sim.ini")
gt() { grep "^  \"ground_truth\"" "$1" | grep -o "\"$2\": [0-9.]*" | head -1 | sed 's/.*: //'; }
pct() { awk -v x="$1" 'BEGIN { printf "%.2f", 100 * x }'; }
info() { "$app" map-info "$1" | head -1 | grep -o '[0-9]* keyframes' | cut -d' ' -f1; }
# Frames per second at the median time per frame (timing.json; a loaded machine gives less).
fps() { grep -o '"ms_per_frame": {"median": [0-9.]*' "$1" | sed 's/.*: //' | awk '{ if ($1 > 0) printf "%.0f", 1000 / $1; else print "-" }'; }

first="${runs[0]}"
[ -f "$out/all_1.kfmap" ] ||
  "$app" survey -q -i "$eval_dir/$first.rawlog" --gt "$eval_dir/$first.tum" -o "$out/all_1.kfmap" -c "$here/config/vo_sim.ini" >/dev/null
[ -f "$out/learn_1.kfmap" ] || cp "$out/all_1.kfmap" "$out/learn_1.kfmap"
echo "order: ${runs[*]}"
echo
echo "| step | live run | all runs before: coverage % | false | MB | keyframes | fps | learnt map: coverage % | false | MB | keyframes | fps |"
echo "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for ((k = 1; k < ${#runs[@]}; k++)); do
  r="${runs[$k]}"
  row="| $k | $r |"
  for way in all learn; do
    map="$out/${way}_$k.kfmap" next="$out/${way}_$((k + 1)).kfmap" d="$out/loc--$k--$r--$way"
    extra=()
    [ $way = learn ] && extra=(--learn "$next")
    if [ ! -f "$d/summary.json" ]; then
      rm -rf "$d"
      "$app" localise -q -m "$map" -i "$eval_dir/$r.rawlog" --gt "$eval_dir/$r.tum" -o "$d" "${cfg[@]}" "${extra[@]}" \
        > "$d.log"
    fi
    [ $way = all ] && [ ! -f "$next" ] &&
      "$app" survey -q --append "$map" -i "$eval_dir/$r.rawlog" --gt "$eval_dir/$r.tum" -o "$next" \
        --links "$out/links_$((k + 1)).csv" "${cfg[@]}" > "$out/append_$((k + 1)).log"
    mb=$(awk -v b="$(stat -c %s "$map")" 'BEGIN { printf "%.1f", b / 1e6 }')
    row="$row $(pct "$(gt "$d/summary.json" true_coverage_in_map)") | $(gt "$d/summary.json" false_fixes) | $mb | $(info "$map") | $(fps "$d/timing.json") |"
  done
  echo "$row"
done
for way in all learn; do
  m="$out/${way}_${#runs[@]}.kfmap"
  echo "final $way map: $(stat -c %s "$m") bytes, $(info "$m") keyframes"
done
grep -h "^learn:" "$out"/loc--*--learn.log 2>/dev/null | sed 's/^/  /' || true
echo "(outputs in $out)"
