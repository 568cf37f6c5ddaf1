#!/usr/bin/env bash
# Localisation coverage on the simulator against the invariant's alpha
# (docs/calibration.md, "Localisation coverage with calibrated vs wrong α").
# For every alpha given, config/vo_sim.ini's [invariant] section is replaced
# by `alpha = A`, `beta = 1 - A` (or the pair A/B given as A:B), keeping its
# linearisation and 8-bit mapping (scale 128, offset 0.5), so only the
# projection direction changes. Each traversal is surveyed into a map with
# that section (the map's invariant descriptors depend on it), and every other
# traversal is localised against it with the invariant localiser alone and
# with the combined system (mono then invariant). The mono baseline does not
# depend on alpha and is run once. Prints two markdown tables (true coverage
# over in-map frames; false fixes in brackets when there are any), one row per
# ordered pair and a mean row.
#
#   scripts/alpha-coverage.sh [DATADIR] [OUTDIR] [LABEL=ALPHA[:BETA] ...]
#
# With MAPPING=calibrated the 8-bit mapping is calibrated for each alpha
# instead (`shadyloc calibrate-alpha --alpha A` over every 6th frame of every
# rawlog in DATADIR: 0.4 % clipped), so that alpha no longer changes the
# invariant image's contrast.
#
# DATADIR defaults to rawlogs/generated (scripts/make-default-dataset.sh),
# OUTDIR to a temporary directory (maps and runs are kept there and reused on
# a second call). The default alphas are those of docs/calibration.md.
# SHADYLOC_APP overrides build/shadyloc.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="${SHADYLOC_APP:-$here/build/shadyloc}"
data="${1:-$here/rawlogs/generated}"
out="${2:-$(mktemp -d)}"
shift 2 || shift $# || true
alphas=("$@")
if [ ${#alphas[@]} -eq 0 ]; then
  # ref: the camera's black-body reference (sim::blackBodyReferenceAlpha for
  # config/sim.ini's 470/540/620 nm, sigma 30 nm); ref-0.2 / ref-0.1 /
  # ref+0.1: wrong on purpose; paper: the Bumblebee2 datasheet values of
  # McManus et al. (alpha + beta != 1); same-view: the same-view estimate for
  # this camera (InvariantCalibrationSim, noon against morning and evening at
  # one pose); edges: what `calibrate-alpha --rawlog noon.rawlog --every 3`
  # (unsupervised) answers on this data.
  alphas=(ref=0.459 ref-0.2=0.259 ref-0.1=0.359 ref+0.1=0.559 paper=0.48:0.5065 same-view=0.504 edges=0.669)
fi
if [ ! -x "$app" ]; then
  echo "alpha-coverage: '$app' not found: build first" >&2
  exit 1
fi
conds=()
for r in "$data"/*.rawlog; do
  c="$(basename "$r" .rawlog)"
  [ -f "$data/$c.tum" ] || { echo "alpha-coverage: $data/$c.tum missing" >&2; exit 1; }
  conds+=("$c")
done
[ ${#conds[@]} -ge 2 ] || { echo "alpha-coverage: fewer than two rawlogs in $data" >&2; exit 1; }

# vo_sim.ini with its [invariant] section's alpha/beta (or peak wavelengths)
# replaced by the given ones, and with a calibrated mapping its scale and
# offset too; every other key stays.
make_config() {
  local a="$1" b="$2" dst="$3" sc="" of=""
  if [ "${MAPPING:-fixed}" = calibrated ]; then
    local rl=() r
    for r in "$data"/*.rawlog; do rl+=(--rawlog "$r"); done
    "$app" calibrate-alpha --linearise none "${rl[@]}" --every 6 --alpha "$a" --beta "$b" -o "$dst.mapping" > "$dst.mapping.log"
    sc="$(sed -n 's/^scale = //p' "$dst.mapping.ini")"
    of="$(sed -n 's/^offset = //p' "$dst.mapping.ini")"
  fi
  awk -v a="$a" -v b="$b" -v sc="$sc" -v of="$of" '
    /^\[/ { insec = ($0 == "[invariant]") }
    insec && /^(peak_wavelength_(blue|green|red)_nm|alpha|beta)[ \t]*=/ { next }
    insec && sc != "" && /^(scale|offset)[ \t]*=/ { next }
    { print }
    $0 == "[invariant]" { print "alpha = " a; print "beta = " b; if (sc != "") { print "scale = " sc; print "offset = " of } }
  ' "$here/config/vo_sim.ini" > "$dst.tmp"
  mv "$dst.tmp" "$dst"
}

# "key": value of summary.json's ground_truth object.
field() { grep -o "\"$2\": [0-9.]*" "$1" | head -1 | sed 's/.*: //'; }
cell() {
  local s="$1/summary.json" f
  f="$(field "$s" false_fixes)"
  awk -v x="$(field "$s" true_coverage_in_map)" -v f="$f" \
    'BEGIN { printf "%.1f", 100 * x; if (f > 0) printf " (%d false)", f }'
}

labels=()
for spec in "${alphas[@]}"; do
  label="${spec%%=*}"
  ab="${spec#*=}"
  a="${ab%%:*}"
  if [ "$ab" = "$a" ]; then b="$(awk -v a="$a" 'BEGIN { printf "%.6g", 1 - a }')"; else b="${ab#*:}"; fi
  labels+=("$label")
  d="$out/$label"
  mkdir -p "$d/maps"
  # Maps and runs in OUTDIR are reused only when they were made with this
  # very config (the mapping's calibration is deterministic).
  make_config "$a" "$b" "$d/vo.ini.new"
  if [ -f "$d/vo.ini" ] && ! cmp -s "$d/vo.ini" "$d/vo.ini.new"; then
    echo "alpha-coverage: $d holds outputs of another config for '$label' (other alpha or MAPPING): use another OUTDIR" >&2
    exit 1
  fi
  mv "$d/vo.ini.new" "$d/vo.ini"
  echo "$label: alpha $a, beta $b, mapping ${MAPPING:-fixed}" > "$d/alpha.txt"
  for c in "${conds[@]}"; do
    [ -f "$d/maps/$c.kfmap" ] || "$app" survey -q -i "$data/$c.rawlog" -o "$d/maps/$c.kfmap" -c "$d/vo.ini" --gt "$data/$c.tum" >/dev/null
  done
  for m in "${conds[@]}"; do
    for l in "${conds[@]}"; do
      [ "$m" = "$l" ] && continue
      modes=(invariant mono,invariant)
      [ "$label" = "${labels[0]}" ] && modes=(mono "${modes[@]}")
      for mode in "${modes[@]}"; do
        r="$d/$m--$l--${mode/,/+}"
        [ -f "$r/summary.json" ] || "$app" localise -q -m "$d/maps/$m.kfmap" -i "$data/$l.rawlog" -o "$r" \
          -c "$d/vo.ini" -c "$here/config/localise_sim.ini" --gt "$data/$l.tum" --localisers "$mode" >/dev/null
      done
    done
  done
done

table() {  # $1: mode (invariant | mono+invariant), $2: title
  local mode="$1" header="| map | live | mono (any α) |" rule="|---|---|---|" lab m l row
  for lab in "${labels[@]}"; do
    header="$header $lab α=$(sed 's/.*alpha \([^,]*\),.*/\1/' "$out/$lab/alpha.txt") |"
    rule="$rule---|"
  done
  echo "$2"
  echo
  echo "$header"
  echo "$rule"
  local sums=() n=0 i
  for m in "${conds[@]}"; do
    for l in "${conds[@]}"; do
      [ "$m" = "$l" ] && continue
      row="| $m | $l | $(cell "$out/${labels[0]}/$m--$l--mono") |"
      sums[0]=$(awk -v s="${sums[0]:-0}" -v x="$(field "$out/${labels[0]}/$m--$l--mono/summary.json" true_coverage_in_map)" 'BEGIN { print s + x }')
      i=1
      for lab in "${labels[@]}"; do
        row="$row $(cell "$out/$lab/$m--$l--$mode") |"
        sums[$i]=$(awk -v s="${sums[$i]:-0}" -v x="$(field "$out/$lab/$m--$l--$mode/summary.json" true_coverage_in_map)" 'BEGIN { print s + x }')
        i=$((i + 1))
      done
      n=$((n + 1))
      echo "$row"
    done
  done
  row="| **mean** | |"
  for s in "${sums[@]}"; do row="$row **$(awk -v s="$s" -v n="$n" 'BEGIN { printf "%.1f", 100 * s / n }')** |"; done
  echo "$row"
  echo
}
table invariant "True coverage of in-map frames [%], invariant localiser alone:"
table mono+invariant "True coverage of in-map frames [%], combined system (mono, then invariant):"
echo "(outputs in $out)"
