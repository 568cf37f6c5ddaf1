#!/usr/bin/env bash
# Active search measured (McManus et al. 2014, Section II-B; docs/localisation.md,
# "Active search"): the combined system on every ordered pair of different
# lighting conditions of the simulator's dataset, once per search region of
# the localisers ([localiser] search): `gate` (the chi-square gate of the
# predicted measurement, the default), `window` (a fixed circle of window_px =
# 40 px around the predicted projection) and `global` (every measurement of
# the live frame, i.e. global BRIEF matching to the keyframe). Prints a
# markdown table per pair and the totals: true coverage over in-map frames,
# false fixes, mean inliers per solved frame of each localiser, and the
# median time per frame of each localiser and of the whole system [ms].
#
#   scripts/localise-sim-search.sh [DATADIR] [OUTDIR] [extra `shadyloc localise` options]
#
# DATADIR defaults to rawlogs/generated (scripts/make-default-dataset.sh),
# OUTDIR to a temporary directory (maps in OUTDIR/maps are reused, e.g. those
# of scripts/localise-sim-pairs.sh). Times are of a shared machine: compare
# them within one run of this script.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="${SHADYLOC_APP:-$here/build/shadyloc}"
data="${1:-$here/rawlogs/generated}"
out="${2:-$(mktemp -d)}"
shift 2 || shift $# || true
ini="${SHADYLOC_LOCALISE_INI:-$here/config/localise_sim.ini}"
if [ ! -x "$app" ]; then
  echo "localise-sim-search: '$app' not found: build first" >&2
  exit 1
fi
grep -q '^search = ' "$ini" || { echo "localise-sim-search: $ini has no 'search = ' line" >&2; exit 1; }
mkdir -p "$out/maps" "$out/configs"
conds=()
for r in "$data"/*.rawlog; do
  c="$(basename "$r" .rawlog)"
  [ -f "$data/$c.tum" ] || { echo "localise-sim-search: $data/$c.tum missing" >&2; exit 1; }
  conds+=("$c")
  [ -f "$out/maps/$c.kfmap" ] || "$app" survey -q -i "$r" -o "$out/maps/$c.kfmap" -c "$here/config/vo_sim.ini" --gt "$data/$c.tum" >/dev/null
done
modes=(gate window global)
for s in "${modes[@]}"; do
  sed "s/^search = [a-z]*/search = $s/" "$ini" > "$out/configs/localise_$s.ini"
done

gt() { grep '^  "ground_truth"' "$1" | grep -o "\"$2\": [0-9.]*" | head -1 | sed 's/.*: //'; }
# Median time [ms] from timing.json: total, or a localiser's.
ms_total() { grep -o '"ms_per_frame": {"median": [0-9.]*' "$1" | sed 's/.*: //'; }
ms_loc() { grep -o "\"$2\": {\"median\": [0-9.]*" "$1" | sed 's/.*: //'; }
# Sum and count of a localiser's inliers over the frames where it solved a pose.
inliers() {
  awk -F, -v ch="$2" 'NR == 1 { for (i = 1; i <= NF; i++) { if ($i == ch "_inliers") a = i; if ($i == ch "_status") b = i }; next }
    $b == "ok" || $b == "unconfirmed" || $b == "uncertain" || $b == "prediction_inconsistent" || $b == "motion_inconsistent" { s += $a; n++ }
    END { print s + 0, n + 0 }' "$1"
}

declare -A T F IN_M N_M IN_I N_I MS MSM MSI RUNS
echo "| map | live | true coverage [%] gate / window / global | false fixes | inliers mono | inliers invariant | ms/frame (system) |"
echo "|---|---|---|---|---|---|---|"
for m in "${conds[@]}"; do
  for l in "${conds[@]}"; do
    [ "$m" = "$l" ] && continue
    cov="" fal="" inm="" ini_="" mss=""
    for s in "${modes[@]}"; do
      d="$out/$m--$l--$s"
      "$app" localise -q -m "$out/maps/$m.kfmap" -i "$data/$l.rawlog" -o "$d" -c "$here/config/vo_sim.ini" \
        -c "$out/configs/localise_$s.ini" --gt "$data/$l.tum" "$@" >/dev/null
      sj="$d/summary.json"
      cov="$cov${cov:+ / }$(awk -v x="$(gt "$sj" true_coverage_in_map)" 'BEGIN { printf "%.1f", 100 * x }')"
      fal="$fal${fal:+ / }$(gt "$sj" false_fixes)"
      read -r sm nm < <(inliers "$d/frames.csv" mono)
      read -r si ni < <(inliers "$d/frames.csv" invariant)
      inm="$inm${inm:+ / }$(awk -v s="$sm" -v n="$nm" 'BEGIN { printf "%.0f", n ? s / n : 0 }')"
      ini_="$ini_${ini_:+ / }$(awk -v s="$si" -v n="$ni" 'BEGIN { printf "%.0f", n ? s / n : 0 }')"
      mss="$mss${mss:+ / }$(ms_total "$d/timing.json")"
      T[$s]=$(( ${T[$s]:-0} + $(gt "$sj" true_fixes) ))
      F[$s]=$(( ${F[$s]:-0} + $(gt "$sj" false_fixes) ))
      IN_M[$s]=$(( ${IN_M[$s]:-0} + sm )); N_M[$s]=$(( ${N_M[$s]:-0} + nm ))
      IN_I[$s]=$(( ${IN_I[$s]:-0} + si )); N_I[$s]=$(( ${N_I[$s]:-0} + ni ))
      MS[$s]="${MS[$s]:-} $(ms_total "$d/timing.json")"
      MSM[$s]="${MSM[$s]:-} $(ms_loc "$d/timing.json" mono)"
      MSI[$s]="${MSI[$s]:-} $(ms_loc "$d/timing.json" invariant)"
    done
    echo "| $m | $l | $cov | $fal | $inm | $ini_ | $mss |"
  done
done
med() { tr ' ' '\n' | grep . | sort -g | awk '{ a[NR] = $1 } END { printf "%.1f", NR % 2 ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2 }'; }
echo
echo "| search | true fixes | false fixes | mean inliers mono / invariant (per solved frame) | ms/frame median over runs: mono localiser / invariant localiser / system |"
echo "|---|---|---|---|---|"
for s in "${modes[@]}"; do
  echo "| $s | ${T[$s]} | ${F[$s]} | $(awk -v a="${IN_M[$s]}" -v b="${N_M[$s]}" 'BEGIN { printf "%.1f", b ? a / b : 0 }') / $(awk -v a="${IN_I[$s]}" -v b="${N_I[$s]}" 'BEGIN { printf "%.1f", b ? a / b : 0 }') | $(echo "${MSM[$s]}" | med) / $(echo "${MSI[$s]}" | med) / $(echo "${MS[$s]}" | med) |"
done
echo
echo "(outputs in $out)"
