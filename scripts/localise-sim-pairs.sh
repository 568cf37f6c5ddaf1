#!/usr/bin/env bash
# Localisation on the simulator, every ordered pair of different lighting
# conditions (docs/localisation.md, "Coverage on the simulator"): a map of
# each traversal (shadyloc survey --gt), then each other traversal localised
# against it three times: the baseline (--localisers mono), the invariant
# localiser alone (--localisers invariant) and the combined system. Prints a
# markdown table of true coverage over in-map frames and false fixes.
#
#   scripts/localise-sim-pairs.sh [DATADIR] [OUTDIR] [extra `shadyloc localise` options]
#
# DATADIR defaults to rawlogs/generated (scripts/make-default-dataset.sh),
# OUTDIR to a temporary directory. Maps are built with config/vo_sim.ini;
# localise runs with config/vo_sim.ini and config/localise_sim.ini.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="${SHADYLOC_APP:-$here/build/shadyloc}"
data="${1:-$here/rawlogs/generated}"
out="${2:-$(mktemp -d)}"
shift 2 || shift $# || true
if [ ! -x "$app" ]; then
  echo "localise-sim-pairs: '$app' not found: build first" >&2
  exit 1
fi
mkdir -p "$out/maps"
conds=()
for r in "$data"/*.rawlog; do
  c="$(basename "$r" .rawlog)"
  [ -f "$data/$c.tum" ] || { echo "localise-sim-pairs: $data/$c.tum missing" >&2; exit 1; }
  conds+=("$c")
  [ -f "$out/maps/$c.kfmap" ] || "$app" survey -q -i "$r" -o "$out/maps/$c.kfmap" -c "$here/config/vo_sim.ini" --gt "$data/$c.tum" >/dev/null
done

# "key": value of summary.json's ground_truth object and localisers list.
field() { grep -o "\"$2\": [0-9.]*" "$1" | head -1 | sed 's/.*: //'; }
pct() { awk -v x="$1" 'BEGIN { printf "%.1f", 100 * x }'; }

echo "| map | live | baseline (mono) | invariant alone | combined | false fixes (mono / inv / comb) |"
echo "|---|---|---|---|---|---|"
for m in "${conds[@]}"; do
  for l in "${conds[@]}"; do
    [ "$m" = "$l" ] && continue
    row="| $m | $l |"
    falses=""
    for mode in mono invariant mono,invariant; do
      d="$out/$m--$l--${mode/,/+}"
      "$app" localise -q -m "$out/maps/$m.kfmap" -i "$data/$l.rawlog" -o "$d" -c "$here/config/vo_sim.ini" \
        -c "$here/config/localise_sim.ini" --gt "$data/$l.tum" --localisers "$mode" "$@" >/dev/null
      row="$row $(pct "$(field "$d/summary.json" true_coverage_in_map)") |"
      falses="$falses${falses:+ / }$(field "$d/summary.json" false_fixes)"
    done
    echo "$row $falses |"
  done
done
echo
echo "(outputs in $out)"
