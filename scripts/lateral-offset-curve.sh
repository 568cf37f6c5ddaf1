#!/usr/bin/env bash
# Coverage against lateral offset (docs/localisation.md, "Patches that follow
# the viewpoint"): the simulator renders one survey (noon light, in its lane)
# and one live traversal in other light (overcast) at each offset to the
# side of it; each live run is localised against the survey's map by the
# baseline, the invariant localiser alone and the combined system, with
# patches warped to the predicted viewpoint and without. Prints a markdown
# table of true coverage over in-map frames and false fixes.
#
#   scripts/lateral-offset-curve.sh [OUTDIR] [OFFSETS...]
#
# OFFSETS default to 0 0.5 1 1.75 2.5 3.5 (m, to the left: towards the other
# lane). OUTDIR defaults to a temporary directory; rendered runs and the map
# in it are reused when present.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="${SHADYLOC_APP:-$here/build/shadyloc}"
out="${1:-$(mktemp -d)}"
shift || true
offsets=("$@")
[ ${#offsets[@]} -gt 0 ] || offsets=(0 0.5 1 1.75 2.5 3.5)
[ -x "$app" ] || { echo "lateral-offset-curve: '$app' not found: build first" >&2; exit 1; }
mkdir -p "$out"

# The simulator's default world and camera, with these traversals instead of its own.
ini="$out/sim_lateral.ini"
names="survey_noon"
{
  awk '/^\[traversal\./ { exit } { print }' "$here/config/sim.ini" | grep -v '^traversals *='
  echo "[traversal.survey_noon]"
  awk '/^\[traversal\.noon\]/ { on = 1; next } /^\[/ { on = 0 } on' "$here/config/sim.ini" |
    sed 's/^lateral_offset_m *=.*/lateral_offset_m = 0.0/'
  for o in "${offsets[@]}"; do
    n="overcast_${o/./_}m"
    names="$names $n"
    echo "[traversal.$n]"
    awk '/^\[traversal\.overcast\]/ { on = 1; next } /^\[/ { on = 0 } on' "$here/config/sim.ini" |
      sed "s/^lateral_offset_m *=.*/lateral_offset_m = $o/"
  done
} > "$ini.tmp"
# The traversal list belongs to [sim]: put it right under the section line.
sed "s/^\[sim\]\$/[sim]\ntraversals = $names/" "$ini.tmp" > "$ini"
rm -f "$ini.tmp"
missing=0
for n in $names; do [ -f "$out/$n.rawlog" ] || missing=1; done
[ $missing = 0 ] || "$app" sim -q -c "$ini" -o "$out"
[ -f "$out/survey_noon.kfmap" ] ||
  "$app" survey -q -i "$out/survey_noon.rawlog" -o "$out/survey_noon.kfmap" -c "$here/config/vo_sim.ini" \
    --gt "$out/survey_noon.tum" >/dev/null

gt() { grep '^  "ground_truth"' "$1" | grep -o "\"$2\": [0-9.]*" | head -1 | sed 's/.*: //'; }
pct() { awk -v x="$1" 'BEGIN { printf "%.1f", 100 * x }'; }
printf '[localiser]\nwarp_patches = false\n' > "$out/unwarped.ini"

echo "| offset (m) | patches | baseline (mono) | invariant alone | combined | false fixes: baseline / invariant / combined |"
echo "|---:|---|---:|---:|---:|---|"
for o in "${offsets[@]}"; do
  n="overcast_${o/./_}m"
  for warp in warped unwarped; do
    extra=()
    [ $warp = unwarped ] && extra=(-c "$out/unwarped.ini")
    row="| $o | $warp |"
    falses=""
    for mode in mono invariant mono,invariant; do
      d="$out/loc--$n--$warp--${mode/,/+}"
      [ -f "$d/summary.json" ] ||
        "$app" localise -q -m "$out/survey_noon.kfmap" -i "$out/$n.rawlog" -o "$d" -c "$here/config/vo_sim.ini" \
          -c "$here/config/localise_sim.ini" "${extra[@]}" --gt "$out/$n.tum" --localisers "$mode" >/dev/null
      row="$row $(pct "$(gt "$d/summary.json" true_coverage_in_map)") |"
      falses="$falses${falses:+ / }$(gt "$d/summary.json" false_fixes)"
    done
    echo "$row $falses |"
  done
done
echo "(outputs in $out)"
