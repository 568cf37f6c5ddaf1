#!/usr/bin/env bash
# Maps of several experiences in time order (docs/map.md, "Experiences"):
# the runs of EVAL_DIR in the order given, each localised by the combined
# system against the map of the runs before it, two ways:
#   all:   every run before appended as an experience (`survey --append`);
#   learn: the map grown only where a run went blind (`localise --learn`).
# Prints a markdown table per step: true coverage (in-map frames), false
# fixes, map size and keyframes, and frames per second of the live run; the
# same per step in OUTDIR/steps.tsv, drawn (with gnuplot) as
# OUTDIR/coverage_by_experiences.png: coverage and map size per step, both
# ways (step k's map of all runs before holds k experiences).
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
runs_in() { "$app" map-info "$1" | head -1 | grep -o '[0-9]* run(s)' | cut -d' ' -f1; }
# Frames per second at the median time per frame (timing.json; a loaded machine gives less).
fps() { grep -o '"ms_per_frame": {"median": [0-9.]*' "$1" | sed 's/.*: //' | awk '{ if ($1 > 0) printf "%.0f", 1000 / $1; else print "-" }'; }

first="${runs[0]}"
[ -f "$out/all_1.kfmap" ] ||
  "$app" survey -q -i "$eval_dir/$first.rawlog" --gt "$eval_dir/$first.tum" -o "$out/all_1.kfmap" -c "$here/config/vo_sim.ini" >/dev/null
[ -f "$out/learn_1.kfmap" ] || cp "$out/all_1.kfmap" "$out/learn_1.kfmap"
echo "order: ${runs[*]}"
echo
printf "step\tlive\tall_experiences\tall_coverage\tall_false\tall_mb\tall_fps\tlearn_experiences\tlearn_coverage\tlearn_false\tlearn_mb\tlearn_fps\n" > "$out/steps.tsv"
echo "| step | live run | all runs before: coverage % | false | MB | keyframes | fps | learnt map: coverage % | false | MB | keyframes | fps |"
echo "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for ((k = 1; k < ${#runs[@]}; k++)); do
  r="${runs[$k]}"
  row="| $k | $r |"
  tsv="$k\t$r"
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
    cov="$(pct "$(gt "$d/summary.json" true_coverage_in_map)")" false="$(gt "$d/summary.json" false_fixes)" f="$(fps "$d/timing.json")"
    row="$row $cov | $false | $mb | $(info "$map") | $f |"
    tsv="$tsv\t$(runs_in "$map")\t$cov\t$false\t$mb\t$f"
  done
  echo "$row"
  printf "$tsv\n" >> "$out/steps.tsv"
done
for way in all learn; do
  m="$out/${way}_${#runs[@]}.kfmap"
  echo "final $way map: $(stat -c %s "$m") bytes, $(info "$m") keyframes"
done
grep -h "^learn:" "$out"/loc--*--learn.log 2>/dev/null | sed 's/^/  /' || true
# The figure: coverage (left axis) and map size (right axis) against the experiences held.
if command -v gnuplot > /dev/null; then
  png="$out/coverage_by_experiences.png"
  gnuplot <<GP
set terminal pngcairo size 900,440 font 'sans,10' noenhanced
set output '$png.tmp'
set datafile separator tab
set key bottom right
set xlabel 'step k: the live run against the map of the k runs before it (all: k experiences; learnt: see steps.tsv)'
set ylabel 'true coverage of the live run [%]'
set y2label 'map size [MB]'
set yrange [0:105]
set y2range [0:*]
set ytics nomirror
set y2tics
set xtics 1
set title "the first map: ${runs[0]}; then, in order: ${runs[*]:1}" font ',9'
plot '$out/steps.tsv' using 1:4 skip 1 with linespoints lw 2 pt 7 title 'all runs before: coverage', \
     '' using 1:9 skip 1 with linespoints lw 2 pt 5 title 'learnt map: coverage', \
     '' using 1:6 skip 1 axes x1y2 with lines dt 2 title 'all runs before: MB', \
     '' using 1:11 skip 1 axes x1y2 with lines dt 3 title 'learnt map: MB'
GP
  mv "$png.tmp" "$png"
  echo "figure: $png"
else
  echo "gnuplot not found: no figure (Debian package gnuplot-nox, installed by scripts/setup.sh)"
fi
echo "(outputs in $out)"
