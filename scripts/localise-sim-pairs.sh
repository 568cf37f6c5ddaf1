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
# localise runs with config/vo_sim.ini and config/localise_sim.ini (or the
# file in SHADYLOC_LOCALISE_INI). Below the table: true and false fixes over
# all pairs per system (inv_in_comb: the invariant localiser's own accepted
# fixes in the combined runs, used or not).
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

# A number from summary.json: gt KEY (the ground_truth object) or ch CHANNEL KEY
# (that localiser's entry of the localisers list).
gt() { grep '^  "ground_truth"' "$1" | grep -o "\"$2\": [0-9.]*" | head -1 | sed 's/.*: //'; }
ch() { grep '^  "localisers"' "$1" | grep -o "{\"channel\": \"$2\"[^}]*}" | grep -o "\"$3\": [0-9.]*" | sed 's/.*: //'; }
pct() { awk -v x="$1" 'BEGIN { printf "%.1f", 100 * x }'; }

declare -A tot_true tot_false
echo "| map | live | baseline (mono) | invariant alone | combined | false fixes: baseline / invariant alone / combined (its invariant channel) |"
echo "|---|---|---|---|---|---|"
for m in "${conds[@]}"; do
  for l in "${conds[@]}"; do
    [ "$m" = "$l" ] && continue
    row="| $m | $l |"
    falses=""
    for mode in mono invariant mono,invariant; do
      d="$out/$m--$l--${mode/,/+}"
      "$app" localise -q -m "$out/maps/$m.kfmap" -i "$data/$l.rawlog" -o "$d" -c "$here/config/vo_sim.ini" \
        -c "${SHADYLOC_LOCALISE_INI:-$here/config/localise_sim.ini}" --gt "$data/$l.tum" --localisers "$mode" "$@" >/dev/null
      s="$d/summary.json"
      row="$row $(pct "$(gt "$s" true_coverage_in_map)") |"
      falses="$falses${falses:+ / }$(gt "$s" false_fixes)"
      tot_true[$mode]=$(( ${tot_true[$mode]:-0} + $(gt "$s" true_fixes) ))
      tot_false[$mode]=$(( ${tot_false[$mode]:-0} + $(gt "$s" false_fixes) ))
      if [ "$mode" = mono,invariant ]; then
        falses="$falses ($(ch "$s" invariant false_fixes) of $(ch "$s" invariant accepted))"
        tot_true[inv_in_comb]=$(( ${tot_true[inv_in_comb]:-0} + $(ch "$s" invariant true_fixes) ))
        tot_false[inv_in_comb]=$(( ${tot_false[inv_in_comb]:-0} + $(ch "$s" invariant false_fixes) ))
      fi
    done
    echo "$row $falses |"
  done
done
echo
for k in mono invariant mono,invariant inv_in_comb; do
  t=${tot_true[$k]:-0}; f=${tot_false[$k]:-0}
  echo "$k: $t true fixes, $f false ($(awk -v t="$t" -v f="$f" 'BEGIN { printf "%.2f", (t + f) ? 100 * f / (t + f) : 0 }') %)"
done
echo "(outputs in $out)"
