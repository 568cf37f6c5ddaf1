#!/usr/bin/env bash
# What a tighter sigma cap would take from each localiser's accepted fixes
# (docs/localisation.md, "Per-localiser caps"): reads the solves.csv of
# every pair of an evaluation's system and, for each localiser and each cap,
# counts the accepted solves with ground truth whose sigma (largest
# translational axis) is within the cap, the false ones among them (off by
# more than 0.5 m or 2 deg, as the evaluation judges) and the exact
# (Clopper-Pearson, as the evaluation's summary) 95 % upper bound on the
# false share. A first look only: a fix the cap removes also changes the
# track of the frames after it, so an operating point is confirmed by
# evaluating again with the cap set.
#
#   scripts/sigma-cap-tradeoff.sh EVAL_DIR [CAPS...]
#
# CAPS (m) default to 0.14 0.13 0.12 0.11 0.10 0.09. SYSTEM (environment)
# chooses the evaluated system: combined (default) or baseline. Prints a
# markdown table; PLOT=OUT.png (environment) also draws it (gnuplot): per
# localiser, the false-fix bound and the share of fixes kept against the cap.
set -euo pipefail
die() { echo "sigma-cap-tradeoff: $*" >&2; exit 1; }
[ $# -ge 1 ] || die "usage: scripts/sigma-cap-tradeoff.sh EVAL_DIR [CAPS...]"
dir="$1"; shift
caps=("$@")
[ ${#caps[@]} -gt 0 ] || caps=(0.14 0.13 0.12 0.11 0.10 0.09)
for c in "${caps[@]}"; do
  [[ "$c" =~ ^[0-9]*\.?[0-9]+$ ]] || die "cap '$c' is not a number of metres"
done
[ -d "$dir/jobs" ] || die "'$dir' has no jobs/ folder: not an evaluation's output"
shopt -s nullglob
system="${SYSTEM:-combined}"
[[ "$system" =~ ^(combined|baseline)$ ]] || die "SYSTEM '$system' is neither combined nor baseline"
files=("$dir"/jobs/pair_*__"$system"/solves.csv)
[ ${#files[@]} -gt 0 ] || die "'$dir/jobs' has no pair_*__${system}/solves.csv"

if [ -n "${PLOT:-}" ]; then
  command -v gnuplot >/dev/null || die "PLOT: gnuplot not found (apt-get install gnuplot-nox)"
fi
table="$(awk -v caps="${caps[*]}" '
  # The exact upper end of the 95 % interval of k false in n (as the evaluation reports it).
  function cdf(k, n, p,   i, lt, m, s) {
    lt[0] = n * log(1 - p); m = lt[0]
    for (i = 1; i <= k; i++) { lt[i] = lt[i - 1] + log((n - i + 1) / i) + log(p / (1 - p)); if (lt[i] > m) m = lt[i] }
    s = 0; for (i = 0; i <= k; i++) s += exp(lt[i] - m)
    return exp(m + log(s))
  }
  function upper(k, n,   a, b, x, it) {
    if (n == 0 || k >= n) return 1
    a = 0; b = 1
    for (it = 0; it < 100; it++) { x = (a + b) / 2; if (cdf(k, n, x) > 0.025) a = x; else b = x }
    return (a + b) / 2
  }
  BEGIN { nc = split(caps, cap, " ") }
  FNR == 1 {
    for (i = 1; i <= NF; i++) col[$i] = i
    if (!("sigma_m" in col) || !("err_m" in col) || !("err_deg" in col) || !("status" in col) || !("channel" in col)) {
      print "sigma-cap-tradeoff: " FILENAME ": not a solves.csv (columns missing)" > "/dev/stderr"; exit 1
    }
    next
  }
  $col["status"] == "ok" && $col["err_m"] != "" {
    ch = $col["channel"]
    if (!(ch in all)) order[++nch] = ch
    all[ch]++
    bad = ($col["err_m"] + 0 > 0.5 || $col["err_deg"] + 0 > 2)
    for (c = 1; c <= nc; c++)
      if ($col["sigma_m"] + 0 <= cap[c] + 0) { kept[ch, c]++; falsek[ch, c] += bad }
  }
  END {
    print "| localiser | cap [m] | accepted fixes kept | of all accepted [%] | false among them | exact 95 % upper bound [%] |"
    print "|---|---:|---:|---:|---:|---:|"
    for (o = 1; o <= nch; o++) {
      ch = order[o]
      for (c = 1; c <= nc; c++) {
        n = kept[ch, c] + 0; k = falsek[ch, c] + 0
        printf "| %s | %s | %d | %.1f | %d | %.3f |\n", ch, cap[c], n, 100 * n / all[ch], k, 100 * upper(k, n)
      }
    }
  }' FS=, "${files[@]}")"
echo "$table"
[ -n "${PLOT:-}" ] || exit 0
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp" "$PLOT.partial.png"' EXIT
# One data file per localiser: cap, kept %, bound %.
echo "$table" | awk -F'|' -v d="$tmp" 'NR > 2 { gsub(/ /, "", $2); print $3 + 0, $5 + 0, $7 + 0 > (d "/" $2 ".dat") }'
plots=""
colours=("#d62728" "#2ca02c" "#1f77b4" "#9467bd")
i=0
for f in "$tmp"/*.dat; do
  l="$(basename "$f" .dat)"; c="${colours[$(( i % 4 ))]}"; i=$(( i + 1 ))
  plots="$plots${plots:+, }\"$f\" using 1:3 with linespoints pt 7 lc rgb \"$c\" title \"$l: false-fix bound\", \"$f\" using 1:2 axes x1y2 with linespoints dt 2 pt 6 lc rgb \"$c\" title \"$l: fixes kept\""
done
gnuplot <<GP
set terminal pngcairo size 900,540 font "DejaVu Sans,10"
set output "$PLOT.partial.png"
set termoption noenhanced
set title "Each localiser's sigma cap: false fixes against fixes kept ($system system, $(basename "$dir"))"
set xlabel "max_sigma_m: no fix above this sigma [m]"
set ylabel "exact 95 % upper bound on false fixes [%]"
set y2label "accepted fixes kept [%]"
set ytics nomirror
set y2tics
set grid
set key outside bottom center horizontal
set bmargin 7
set arrow from graph 0, first 0.1 to graph 1, first 0.1 nohead dt 3 lc rgb "black"
set label "0.1 %" at graph 0.01, first 0.1 offset 0,0.6
plot $plots
GP
mv "$PLOT.partial.png" "$PLOT"
