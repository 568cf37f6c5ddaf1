#!/usr/bin/env bash
# The keyframe map's size-coverage curve on the simulator (docs/map.md,
# "Size against coverage"): for each map setting, a map of every traversal
# of DATADIR (shadyloc survey with config/vo_sim.ini, its [map] keys
# overridden by the setting), their size per channel [MB/km over the four
# maps together], and every ordered pair of different traversals localised
# twice: the baseline (--localisers mono) and the combined system, with
# config/localise_sim.ini. Prints one markdown row per setting and writes the
# per-pair true coverage to OUTDIR/pairs.tsv.
#
#   scripts/map-size-curve.sh DATADIR OUTDIR SETTING...
#   SETTING: name:key=value,key=value   ([map] keys), e.g.
#   scripts/map-size-curve.sh rawlogs/generated /tmp/curve all:landmarks_per_keyframe=0 \
#       k120:landmarks_per_keyframe=120,landmark_selection=reobserved
#
# The binary and library are copied into OUTDIR first, so rebuilding while
# it runs changes nothing.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [ $# -lt 3 ]; then
  echo "usage: $0 DATADIR OUTDIR name:key=value,... [more settings]" >&2
  exit 2
fi
data="$1"
out="$2"
shift 2
[ -x "$here/build/shadyloc" ] || { echo "map-size-curve: build/shadyloc not found: build first" >&2; exit 1; }
mkdir -p "$out/bin"
cp "$here/build/shadyloc" "$here"/build/libshadyloc_{localisation,tools}.so* "$out/bin/"
app="$out/bin/shadyloc"
export LD_LIBRARY_PATH="$out/bin${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
conds=()
for r in "$data"/*.rawlog; do conds+=("$(basename "$r" .rawlog)"); done
[ ${#conds[@]} -ge 2 ] || { echo "map-size-curve: fewer than two rawlogs in $data" >&2; exit 1; }

field() { grep -o "\"$2\": [0-9.]*" "$1" | head -1 | sed 's/.*: //'; }
[ -f "$out/pairs.tsv" ] || printf "setting\tmap\tlive\tbaseline\tcombined\tfalse_baseline\tfalse_combined\n" >"$out/pairs.tsv"
echo "| setting | mono MB/km | invariant MB/km | mono meas/kf | invariant meas/kf | baseline mean (min) % | combined mean (min) % | pairs combined < baseline | false fixes (base / comb) |"
echo "|---|---|---|---|---|---|---|---|---|"
for setting in "$@"; do
  name="${setting%%:*}"
  keys="${setting#*:}"
  d="$out/$name"
  mkdir -p "$d/maps"
  ini="$d/vo_map.ini"
  # config/vo_sim.ini with the setting's [map] keys replaced (or added).
  python3 - "$here/config/vo_sim.ini" "$ini" "$keys" <<'EOF'
import re, sys
src, dst, keys = sys.argv[1], sys.argv[2], sys.argv[3]
kv = dict(x.split("=", 1) for x in keys.split(",") if x)
lines, section, seen = [], None, set()
for line in open(src):
    m = re.match(r"\s*\[(.+)\]", line)
    if m:
        if section == "map":
            lines += [f"{k} = {v}\n" for k, v in kv.items() if k not in seen]
        section = m.group(1)
    elif section == "map":
        k = line.split("=", 1)[0].strip()
        if k in kv:
            line, _ = f"{k} = {kv[k]}\n", seen.add(k)
    lines.append(line)
if section == "map":
    lines += [f"{k} = {v}\n" for k, v in kv.items() if k not in seen]
open(dst, "w").write("".join(lines))
EOF
  kb=(0 0) meas=(0 0) metres=0 kfs=0
  for c in "${conds[@]}"; do
    [ -f "$d/maps/$c.kfmap" ] || "$app" survey -q -i "$data/$c.rawlog" -o "$d/maps/$c.kfmap" -c "$ini" --gt "$data/$c.tum" >"$d/maps/$c.log"
    "$app" map-info "$d/maps/$c.kfmap" >"$d/maps/$c.info"
  done
  sizes="$(awk '
    / keyframes, .* m of path/ { k += $2; for (i = 1; i <= NF; i++) if ($i == "m" && $(i+1) == "of") L += $(i-1) }
    /measurements\/keyframe/ { ch = n++ % 2; for (i = 1; i <= NF; i++) if ($i == "kB") kb[ch] += $(i-1); mk[ch] += $1 }
    END { printf "%.2f %.2f %.0f %.0f", kb[0] / 1e3 / (L / 1e3), kb[1] / 1e3 / (L / 1e3), mk[0] / (n / 2), mk[1] / (n / 2) }
  ' "$d"/maps/*.info)"
  read -r mono_mb inv_mb mono_n inv_n <<<"$sizes"
  # A setting run again replaces its rows.
  awk -F'\t' -v s="$name" '$1 != s' "$out/pairs.tsv" >"$out/pairs.tsv.tmp" && mv "$out/pairs.tsv.tmp" "$out/pairs.tsv"
  for m in "${conds[@]}"; do
    for l in "${conds[@]}"; do
      [ "$m" = "$l" ] && continue
      cov=() falses=()
      for mode in mono mono,invariant; do
        o="$d/$m--$l--${mode/,/+}"
        [ -f "$o/summary.json" ] || "$app" localise -q -m "$d/maps/$m.kfmap" -i "$data/$l.rawlog" -o "$o" \
          -c "$here/config/vo_sim.ini" -c "$here/config/localise_sim.ini" --gt "$data/$l.tum" --localisers "$mode" >/dev/null
        cov+=("$(awk -v x="$(field "$o/summary.json" true_coverage_in_map)" 'BEGIN { printf "%.1f", 100 * x }')")
        falses+=("$(field "$o/summary.json" false_fixes)")
      done
      printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\n" "$name" "$m" "$l" "${cov[0]}" "${cov[1]}" "${falses[0]}" "${falses[1]}" >>"$out/pairs.tsv"
    done
  done
  awk -F'\t' -v s="$name" -v a="$mono_mb" -v b="$inv_mb" -v na="$mono_n" -v nb="$inv_n" '
    $1 == s { n++; bs += $4; cs += $5; if (n == 1 || $4 < bmin) bmin = $4; if (n == 1 || $5 < cmin) cmin = $5;
              worse += ($5 < $4); fb += $6; fc += $7 }
    END { printf "| %s | %s | %s | %s | %s | %.1f (%.1f) | %.1f (%.1f) | %d | %d / %d |\n", s, a, b, na, nb, bs / n, bmin, cs / n, cmin, worse, fb, fc }
  ' "$out/pairs.tsv"
done
