#!/usr/bin/env bash
# The acceptance trade-off of docs/localisation.md ("The solve log"): mean
# true coverage against the share of false fixes used, for the baseline and
# the combined system, one point per evaluation (`shadyloc eval` output
# folders run with different acceptance settings, e.g. max_sigma_m).
#
#   scripts/plot-acceptance-tradeoff.sh OUT.png LABEL=EVALDIR [LABEL=EVALDIR ...]
#
# Prints the table it plots (label, system, coverage %, false, fixes, false %).
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 OUT.png LABEL=EVALDIR [LABEL=EVALDIR ...]" >&2; exit 2; }
out="$1"; shift
command -v gnuplot >/dev/null || { echo "plot-acceptance-tradeoff: gnuplot not found (apt-get install gnuplot-nox)" >&2; exit 1; }
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp" "$out.partial.png"' EXIT
python3 - "$tmp" "$@" <<'PY'
import re, sys
tmp, args = sys.argv[1], sys.argv[2:]
rows = []
for a in args:
    if "=" not in a:
        sys.exit(f"plot-acceptance-tradeoff: '{a}' is not LABEL=EVALDIR")
    label, d = a.split("=", 1)
    try:
        t1 = open(f"{d}/table1.md").read()
        sm = open(f"{d}/summary.md").read()
    except OSError as e:
        sys.exit(f"plot-acceptance-tradeoff: {d}: {e.strerror} (an output folder of shadyloc eval?)")
    m = re.search(r"\*\*mean\*\* \| \d+ \| ([\d.]+) \| ([\d.]+) \| ([\d.]+)", t1)
    if not m:
        sys.exit(f"plot-acceptance-tradeoff: {d}/table1.md: no mean row")
    cov = {"baseline": float(m.group(1)), "combined": float(m.group(3))}
    for sysname in ("baseline", "combined"):
        f = re.search(rf"\| {sysname} \| \(used\) \| (\d+) \| (\d+) \| (\d+) \|", sm)
        if not f:
            sys.exit(f"plot-acceptance-tradeoff: {d}/summary.md: no '{sysname} (used)' row")
        fixes, false = int(f.group(1)), int(f.group(3))
        rows.append((label, sysname, cov[sysname], false, fixes, 100.0 * false / fixes if fixes else 0.0))
for sysname in ("baseline", "combined"):
    with open(f"{tmp}/{sysname}.dat", "w") as f:
        for r in sorted((r for r in rows if r[1] == sysname), key=lambda r: r[5]):
            f.write(f"{r[0]} {r[5]:.4f} {r[2]:.2f}\n")
print("| setting | system | true coverage % | false fixes | fixes | false % |")
print("|---|---|---:|---:|---:|---:|")
for r in rows:
    print(f"| {r[0]} | {r[1]} | {r[2]:.2f} | {r[3]} | {r[4]} | {r[5]:.2f} |")
PY
gnuplot <<GP
set terminal pngcairo size 900,540 font "DejaVu Sans,10"
set output "$out.partial.png"
set title "Acceptance: coverage against false fixes (default data, 12 ordered pairs; labels: the setting)"
set xlabel "false fixes among the fixes used [%]"
set ylabel "mean true coverage over in-map frames [%]"
set grid
set key bottom right
set xrange [-0.1:*]
plot "$tmp/combined.dat" using 2:3 with linespoints pt 7 lc rgb "#1f77b4" title "combined (mono + invariant)", \
     "$tmp/combined.dat" using 2:3:1 with labels offset 0,1 tc rgb "#1f77b4" notitle, \
     "$tmp/baseline.dat" using 2:3 with linespoints pt 5 lc rgb "#d62728" title "baseline (mono)", \
     "$tmp/baseline.dat" using 2:3:1 with labels offset 0,-1 tc rgb "#d62728" notitle
GP
mv "$out.partial.png" "$out"
