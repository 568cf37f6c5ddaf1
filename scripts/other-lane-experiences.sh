#!/usr/bin/env bash
# The other lane with a map of two experiences (docs/map.md, "Experiences"): a map
# of one same-lane run (noon_dappled), and the same map with the other-lane
# run (noon_other_lane, 3.5 m aside) appended by `shadyloc survey --append`.
# Live runs: the other lane under other light (rendered here from the
# evaluation set's world and lights, 3.5 m aside) and the five other
# same-lane runs of the 301 m set. Prints a markdown table of true coverage
# (in-map frames) and false fixes of the combined system against each map.
#
#   scripts/other-lane-experiences.sh EVAL_DIR [OUTDIR]
#
# EVAL_DIR holds the 301 m set (scripts/make-eval-dataset.sh). OUTDIR
# defaults to a temporary directory; what is in it already is reused.
# LIGHTS (default "overcast morning_low_sun_left evening_low_sun_right")
# names the evaluation set's traversals whose light the other-lane live
# runs take. About 25 min on 2 cores.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="${SHADYLOC_APP:-$here/build/shadyloc}"
eval_dir="${1:?usage: other-lane-experiences.sh EVAL_DIR [OUTDIR]}"
out="${2:-$(mktemp -d)}"
lights=(${LIGHTS:-overcast morning_low_sun_left evening_low_sun_right})
[ -x "$app" ] || { echo "other-lane-experiences: '$app' not found: build first" >&2; exit 1; }
for r in noon_dappled noon_other_lane; do
  [ -f "$eval_dir/$r.rawlog" ] || { echo "other-lane-experiences: $eval_dir/$r.rawlog missing (scripts/make-eval-dataset.sh)" >&2; exit 1; }
done
mkdir -p "$out"
cfg=(-c "$here/config/vo_sim.ini" -c "$here/config/localise_sim.ini")

# ---- the other lane under other light: the set's world, these traversals
ini="$out/sim_other_lane.ini"
names=""
{
  awk '/^\[traversal\./ { exit } { print }' "$here/config/sim_eval.ini" | grep -v '^traversals *='
  for l in "${lights[@]}"; do
    names="$names ${l}_other_lane"
    echo "[traversal.${l}_other_lane]"
    awk -v s="[traversal.$l]" '$0 == s { on = 1; next } /^\[/ { on = 0 } on' "$here/config/sim_eval.ini" |
      sed 's/^lateral_offset_m *=.*/lateral_offset_m = 3.5/'
  done
} > "$ini.tmp"
sed "s/^\[sim\]\$/[sim]\ntraversals =$names/" "$ini.tmp" > "$ini"
rm -f "$ini.tmp"
missing=0
for n in $names; do [ -f "$out/$n.rawlog" ] || missing=1; done
[ $missing = 0 ] || "$app" sim -q -c "$ini" -o "$out"

# ---- the maps: one experience, and two
[ -f "$out/same_lane.kfmap" ] ||
  "$app" survey -q -i "$eval_dir/noon_dappled.rawlog" --gt "$eval_dir/noon_dappled.tum" -o "$out/same_lane.kfmap" \
    -c "$here/config/vo_sim.ini" >/dev/null
[ -f "$out/two_lanes.kfmap" ] ||
  "$app" survey -q --append "$out/same_lane.kfmap" -i "$eval_dir/noon_other_lane.rawlog" \
    --gt "$eval_dir/noon_other_lane.tum" -o "$out/two_lanes.kfmap" --links "$out/links.csv" "${cfg[@]}" |
    tee "$out/append.log" | grep -E '^(experience|verified|map:)' || true

gt() { grep '^  "ground_truth"' "$1" | grep -o "\"$2\": [0-9.]*" | head -1 | sed 's/.*: //'; }
pct() { awk -v x="$1" 'BEGIN { printf "%.1f", 100 * x }'; }
echo
echo "| live run | lane | one experience (same lane) | two experiences | false fixes: one / two |"
echo "|---|---|---:|---:|---|"
live=()
for l in "${lights[@]}"; do live+=("$out/${l}_other_lane|other"); done
for r in morning_low_sun_left afternoon_side_sun evening_low_sun_right hazy_sun overcast; do
  live+=("$eval_dir/$r|same")
done
for entry in "${live[@]}"; do
  path="${entry%|*}"; lane="${entry#*|}"; n="$(basename "$path")"
  row="| $n | $lane |"; falses=""
  for m in same_lane two_lanes; do
    d="$out/loc--$n--$m"
    [ -f "$d/summary.json" ] ||
      "$app" localise -q -m "$out/$m.kfmap" -i "$path.rawlog" -o "$d" "${cfg[@]}" --gt "$path.tum" >/dev/null
    row="$row $(pct "$(gt "$d/summary.json" true_coverage_in_map)") |"
    falses="$falses${falses:+ / }$(gt "$d/summary.json" false_fixes)"
  done
  echo "$row $falses |"
done
echo "(outputs in $out)"
