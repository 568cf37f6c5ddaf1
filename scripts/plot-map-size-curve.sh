#!/usr/bin/env bash
# The size-coverage plot of docs/map.md ("Size against coverage") from the
# tables scripts/map-size-curve.sh prints: mean true coverage of the
# baseline and of the combined system against the monochrome channel's map
# size, one point per setting (labelled), the 5 MB/km goal marked, and the
# settings at 1.5 m keyframe spacing with 4-bit patches joined as a curve.
#
#   scripts/plot-map-size-curve.sh OUT.png TABLE.md [TABLE.md ...]
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 OUT.png TABLE.md [TABLE.md ...]" >&2; exit 2; }
out="$1"; shift
command -v gnuplot >/dev/null || { echo "plot-map-size-curve: gnuplot not found (apt-get install gnuplot-nox)" >&2; exit 1; }
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp" "$out.partial.png"' EXIT
# Rows: name, mono MB/km, baseline mean, combined mean; "curve" rows are the
# 1.5 m / 4-bit family (names rNNNp4 and all4), sorted by size.
python3 - "$tmp" "$@" <<'PY'
import re, sys
tmp, files = sys.argv[1], sys.argv[2:]
rows = {}
for f in files:
    for line in open(f):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 7 or not re.match(r"^[0-9.]+$", cells[1]):
            continue
        name = cells[0]
        mb = float(cells[1])
        base = float(cells[5].split()[0])
        comb = float(cells[6].split()[0])
        if name in rows and rows[name] != (mb, base, comb):
            sys.exit(f"plot-map-size-curve: setting {name} appears twice with different figures")
        rows[name] = (mb, base, comb)
if not rows:
    sys.exit("plot-map-size-curve: no table rows found in " + " ".join(files))
with open(tmp + "/all.dat", "w") as f:
    for n, (mb, b, c) in sorted(rows.items(), key=lambda kv: kv[1][0]):
        f.write(f"{n} {mb} {b} {c}\n")
sizes = [v[0] for v in rows.values()]
with open(tmp + "/xrange", "w") as f:  # every point inside the plot, whatever the settings
    f.write(f"{min(sizes) / 1.15:.3f}:{max(sizes) * 1.15:.3f}\n")
with open(tmp + "/curve.dat", "w") as f:
    for n, (mb, b, c) in sorted(rows.items(), key=lambda kv: kv[1][0]):
        if re.match(r"^(r[0-9]+p4|all4)$", n):
            f.write(f"{n} {mb} {b} {c}\n")
PY
gnuplot <<GP
set terminal pngcairo size 900,540 font "DejaVu Sans,10"
set output "$out.partial.png"
set title "Keyframe map size against localisation coverage (default data, 12 ordered pairs)"
set xlabel "monochrome channel stored [MB per km of survey] (log scale)"
set ylabel "mean true coverage over in-map frames [%]"
set logscale x
set xrange [$(cat "$tmp/xrange")]
set yrange [0:100]
set grid
set key bottom right
set arrow from 5,0 to 5,100 nohead dt 2 lc rgb "#888888"
set label "5 MB/km goal" at 5.1,4 tc rgb "#666666"
plot "$tmp/curve.dat" using 2:4 with lines lc rgb "#1f77b4" notitle, \
     "$tmp/curve.dat" using 2:3 with lines lc rgb "#d62728" notitle, \
     "$tmp/all.dat" using 2:4 with points pt 7 ps 1.1 lc rgb "#1f77b4" title "combined (mono + invariant)", \
     "$tmp/all.dat" using 2:3 with points pt 5 ps 1.0 lc rgb "#d62728" title "baseline (mono)", \
     "$tmp/all.dat" using 2:4:1 with labels offset 0,0.9 font ",8" notitle
GP
mv "$out.partial.png" "$out"
echo "wrote $out ($(wc -l <"$tmp/all.dat") settings)"
