#!/usr/bin/env bash
# Injected faults, measured as rates (docs/localisation.md, "Injected faults"):
#
#  1. A keyframe offset along the chain: every ordered pair of different
#     traversals of DATADIR (4 runs: 12 pairs) localised by the combined
#     system with [localiser] fault_keyframe_offset = +3 and = -3 (each
#     localiser matches the live frame against the keyframe 3 along the chain
#     from the one it chose, and reports the pose as relative to the chosen
#     one), with ground truth. Per localiser (the joint one too when the
#     config runs it): solves against the wrong
#     keyframe, fixes accepted, false fixes accepted (off by more than 0.5 m
#     or 2 deg); rejection rate = 1 - false accepted / solves, with the exact
#     (Clopper-Pearson) 95 % bound.
#  2. A map of another world: the same traversals rendered with another scene
#     seed ([sim.scene] seed of config/sim.ini + 1 unless OTHER_SEED is set),
#     and every DATADIR run localised against every map of the other world and
#     the other way round. Counts fixes (must be 0), global searches, frames
#     on which a place had been accepted (a localiser ran) and solves.
#
#   scripts/localise-faults.sh [DATADIR] [OUTDIR]
#
# DATADIR defaults to rawlogs/generated (scripts/make-default-dataset.sh);
# OUTDIR to a new temporary directory (kept: per-run outputs and logs;
# the other world's rawlogs and maps are reused when OUTDIR is given again).
# Environment: SHADYLOC_APP (default build/shadyloc), SHADYLOC_LOCALISE_INI
# (default config/localise_sim.ini), SIM_INI (default config/sim.ini),
# OTHER_SEED, OFFSETS (default "3 -3"), OTHER_WORLD (default 1; 0 skips part 2,
# for more keyframe offsets without repeating it). Needs about 10 minutes on 2 cores.
# Exits 1 on bad input or a failed command, 2 when a fault was accepted
# (a false fix under the keyframe offset, or any fix in another world).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="${SHADYLOC_APP:-$here/build/shadyloc}"
data="${1:-$here/rawlogs/generated}"
out="${2:-$(mktemp -d -t shadyloc-faults.XXXXXX)}"
loc_ini="${SHADYLOC_LOCALISE_INI:-$here/config/localise_sim.ini}"
sim_ini="${SIM_INI:-$here/config/sim.ini}"
offsets="${OFFSETS:-3 -3}"
die() { echo "localise-faults: $*" >&2; exit 1; }

[ -x "$app" ] || die "'$app' not found: build first (scripts/setup.sh)"
[ -d "$data" ] || die "data folder '$data' not found (scripts/make-default-dataset.sh makes rawlogs/generated)"
for f in "$loc_ini" "$sim_ini" "$here/config/vo_sim.ini"; do [ -f "$f" ] || die "'$f' not found"; done
conds=()
for r in "$data"/*.rawlog; do
  [ -e "$r" ] || die "no .rawlog in '$data'"
  c="$(basename "$r" .rawlog)"
  [ -f "$data/$c.tum" ] || die "'$data/$c.tum' missing: ground truth is needed to judge fixes"
  conds+=("$c")
done
[ "${#conds[@]}" -ge 2 ] || die "'$data' holds ${#conds[@]} run(s): at least 2 needed"
mkdir -p "$out"/{maps,other,other_maps,runs,logs}
echo "localise-faults: ${#conds[@]} runs of '$data' -> $out" >&2

# run LOG CMD...: a command's output to LOG; on failure, its tail and exit 1.
run() {
  local log="$1"; shift
  if ! "$@" >"$log" 2>&1; then
    tail -n 20 "$log" >&2
    die "failed: $* (log: $log)"
  fi
}
# A number from summary.json: gt KEY (the ground_truth object), top KEY (a
# top-level key), ch CHANNEL KEY (that localiser's entry).
gt() { grep '^  "ground_truth"' "$1" | grep -o "\"$2\": [0-9.]*" | head -1 | sed 's/.*: //'; }
top() { grep "^  \"$2\":" "$1" | head -1 | sed 's/.*: //; s/,$//'; }
ch() { grep '^  "localisers"' "$1" | grep -o "{\"channel\": \"$2\"[^}]*}" | grep -o "\"$3\": [0-9.]*" | sed 's/.*: //'; }
# col CSV NAME CONDITION: rows of frames.csv where the awk CONDITION on the
# column NAME's value `v` holds.
col() {
  awk -F, -v name="$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == name) c = i; if (!c) exit 3; next }
    { v = $c; if ('"$3"') n++ } END { print n + 0 }' "$1" || die "'$1' has no column '$2'"
}
# Exact (Clopper-Pearson) two-sided 95 % upper bound of a proportion, k of n:
# the p with P(X <= k | p) = 0.025, by bisection; the binomial terms summed
# in log space (Clopper and Pearson, Biometrika 26, 1934; the same as
# localisation::clopperPearson).
cp_upper() {
  awk -v k="$1" -v n="$2" 'function cdf(p,   i, t, m, s, lt) {
      if (k >= n) return 1
      lt[0] = n * log(1 - p); m = lt[0]
      for (i = 1; i <= k; i++) { lt[i] = lt[i - 1] + log((n - i + 1) / i) + log(p / (1 - p)); if (lt[i] > m) m = lt[i] }
      s = 0; for (i = 0; i <= k; i++) s += exp(lt[i] - m)
      return exp(m + log(s))
    }
    BEGIN {
      if (n == 0) { print 1; exit }
      if (k >= n) { print 1; exit }
      a = 0; b = 1
      for (it = 0; it < 100; it++) { x = (a + b) / 2; if (cdf(x) > 0.025) a = x; else b = x }
      printf "%.6f\n", (a + b) / 2
    }'
}
pct() { awk -v x="$1" 'BEGIN { printf "%.2f", 100 * x }'; }

survey() {  # survey RAWLOG TUM MAP
  [ -f "$3" ] || run "$out/logs/survey_$(basename "$3").log" \
    "$app" survey -q -i "$1" -o "$3" -c "$here/config/vo_sim.ini" --gt "$2"
}
localise() {  # localise MAP LIVE_DIR LIVE OUTDIR [LOCALISE_INI]
  local m="$1" ld="$2" l="$3" d="$4" ini="${5:-$loc_ini}"
  rm -rf "$d"
  run "$d.log" "$app" localise -q -m "$m" -i "$ld/$l.rawlog" -o "$d" -c "$here/config/vo_sim.ini" -c "$ini" \
    --gt "$ld/$l.tum" --localisers mono,invariant
}

for c in "${conds[@]}"; do survey "$data/$c.rawlog" "$data/$c.tum" "$out/maps/$c.kfmap"; done

# ---- 1. keyframe offset along the chain
status=0
localisers=""
declare -A solved acc falseacc trueacc
echo "## Keyframe offset along the chain (combined system, ${#conds[@]} runs, every ordered pair)"
echo
echo "| offset | localiser | solves against the wrong keyframe | fixes accepted | false fixes accepted | rejection rate [%] | 95 % lower bound [%] |"
echo "|---|---|---|---|---|---|---|"
for off in $offsets; do
  [[ "$off" =~ ^-?[0-9]+$ && "$off" != 0 && "$off" != -0 ]] || die "OFFSETS: '$off' is not a non-zero integer"
  # The localisation config with the one key changed (a key given twice in
  # the -c files together is not relied on).
  ini="$out/localise_offset${off}.ini"
  awk -v off="$off" '/^\[/ { if (sec && !done) { print "fault_keyframe_offset = " off; done = 1 } sec = ($0 ~ /^\[localiser\]/) }
    sec && $1 == "fault_keyframe_offset" { print "fault_keyframe_offset = " off "  ; injected (scripts/localise-faults.sh)"; done = 1; next }
    { print } END { if (!done) { if (!sec) print "[localiser]"; print "fault_keyframe_offset = " off } }' "$loc_ini" >"$ini"
  [ "$(grep -c "^fault_keyframe_offset = $off" "$ini")" = 1 ] || die "could not set fault_keyframe_offset in '$ini'"
  for m in "${conds[@]}"; do
    for l in "${conds[@]}"; do
      [ "$m" = "$l" ] && continue
      d="$out/runs/offset${off}--$m--$l"
      localise "$out/maps/$m.kfmap" "$data" "$l" "$d" "$ini"
      # The channel localisers, and the joint one when the config runs it
      # (its matches come from the channels' searches against the offset keyframe).
      if [ -z "$localisers" ]; then
        localisers="mono invariant"
        hdr="$(head -1 "$d/frames.csv")"
        if [[ ",$hdr," == *",joint_sigma_m,"* ]]; then localisers="$localisers joint"; fi
      fi
      for c in $localisers; do
        key="$off $c"
        # A solve: the localiser reached a pose (sigma_m is written for
        # solved frames only, docs/localisation.md, frames.csv).
        solved[$key]=$(( ${solved[$key]:-0} + $(col "$d/frames.csv" "${c}_sigma_m" 'v != ""') ))
        acc[$key]=$(( ${acc[$key]:-0} + $(ch "$d/summary.json" "$c" accepted) ))
        falseacc[$key]=$(( ${falseacc[$key]:-0} + $(ch "$d/summary.json" "$c" false_fixes) ))
        trueacc[$key]=$(( ${trueacc[$key]:-0} + $(ch "$d/summary.json" "$c" true_fixes) ))
      done
    done
  done
  for c in $localisers; do
    key="$off $c"; n=${solved[$key]}; k=${falseacc[$key]}
    up=$(cp_upper "$k" "$n")
    echo "| $off | $c | $n | ${acc[$key]} | $k | $(pct "$(awk -v k="$k" -v n="$n" 'BEGIN { print n ? 1 - k / n : 1 }')") | $(pct "$(awk -v u="$up" 'BEGIN { print 1 - u }')") |"
  done
done
n=0; k=0; a=0; t=0
for key in "${!solved[@]}"; do
  n=$(( n + solved[$key] )); k=$(( k + falseacc[$key] )); a=$(( a + acc[$key] )); t=$(( t + trueacc[$key] ))
done
up=$(cp_upper "$k" "$n")
echo "| all | $(echo $localisers | sed 's/ / + /g') | $n | $a | $k | $(pct "$(awk -v k="$k" -v n="$n" 'BEGIN { print n ? 1 - k / n : 1 }')") | $(pct "$(awk -v u="$up" 'BEGIN { print 1 - u }')") |"
echo
echo "Keyframe offset: $k of $n wrong-keyframe solves accepted as false fixes (95 % upper bound $(pct "$up") %); $t accepted fixes judged true."
[ "$k" -eq 0 ] || status=2
# An accepted fix judged true under the fault would mean two keyframes 3
# apart within 0.5 m / 2 deg of each other: not on a 1.5 m spaced chain.
[ "$t" -eq 0 ] || echo "localise-faults: $t fixes under the offset were judged true: look at the maps' keyframe spacing" >&2

# ---- 2. a map of another world
if [ "${OTHER_WORLD:-1}" = 0 ]; then exit "$status"; fi
seed=$(awk '/^\[/ { s = ($0 ~ /^\[sim\.scene\]/) } s && $1 == "seed" { print $3; exit }' "$sim_ini")
[[ "$seed" =~ ^[0-9]+$ ]] || die "'$sim_ini': no [sim.scene] seed"
other_seed="${OTHER_SEED:-$(( seed + 1 ))}"
[ "$other_seed" != "$seed" ] || die "OTHER_SEED $other_seed is the data's own scene seed"
other_ini="$out/sim_seed${other_seed}.ini"
awk -v s="$other_seed" '/^\[/ { sc = ($0 ~ /^\[sim\.scene\]/) } sc && $1 == "seed" { sub(/=[ \t]*[0-9]+/, "= " s) } { print }' \
  "$sim_ini" >"$other_ini"
grep -q "^seed = $other_seed" "$other_ini" || die "could not set the scene seed in '$other_ini'"
other="$out/other"
trav="$(IFS=,; echo "${conds[*]}")"
missing=0
for c in "${conds[@]}"; do [ -f "$other/$c.rawlog" ] || missing=1; done
if [ "$missing" = 1 ]; then
  echo "localise-faults: rendering the other world (scene seed $other_seed): $trav" >&2
  # The same traversals (names as in the sim .ini), so the same route, light
  # and frame count; only the layout and textures of the world differ.
  run "$out/logs/sim_other.log" "$app" sim -q -c "$other_ini" -o "$other.tmp" --traversals "$trav"
  rm -rf "$other" && mv "$other.tmp" "$other"
fi
for c in "${conds[@]}"; do survey "$other/$c.rawlog" "$other/$c.tum" "$out/other_maps/$c.kfmap"; done

echo
echo "## A map of another world (scene seed $seed against $other_seed; combined system, every live run against every map)"
echo
echo "| live world | map world | pairs | frames | global searches | frames after an accepted place | solves (mono / invariant) | fixes |"
echo "|---|---|---|---|---|---|---|---|"
tot_fix=0
for dir in "data other" "other data"; do
  read -r lw mw <<<"$dir"
  pairs=0; frames=0; gs=0; placed=0; smono=0; sinv=0; fixes=0
  for m in "${conds[@]}"; do
    for l in "${conds[@]}"; do
      if [ "$lw" = data ]; then ld="$data"; mp="$out/other_maps/$m.kfmap"; else ld="$other"; mp="$out/maps/$m.kfmap"; fi
      d="$out/runs/world-$lw-live-$l--$mw-map-$m"
      localise "$mp" "$ld" "$l" "$d"
      s="$d/summary.json"
      pairs=$(( pairs + 1 ))
      frames=$(( frames + $(top "$s" frames) ))
      gs=$(( gs + $(top "$s" global_searches) ))
      # A localiser runs only with a prediction, i.e. after a verified place.
      placed=$(( placed + $(col "$d/frames.csv" mono_status 'v != "no_prediction"') ))
      smono=$(( smono + $(col "$d/frames.csv" mono_sigma_m 'v != ""') ))
      sinv=$(( sinv + $(col "$d/frames.csv" invariant_sigma_m 'v != ""') ))
      fixes=$(( fixes + $(top "$s" fixes) ))
    done
  done
  name() { [ "$1" = data ] && echo "seed $seed ($(basename "$data"))" || echo "seed $other_seed"; }
  echo "| $(name "$lw") | $(name "$mw") | $pairs | $frames | $gs | $placed | $smono / $sinv | $fixes |"
  tot_fix=$(( tot_fix + fixes ))
done
echo
echo "Another world: $tot_fix fixes."
[ "$tot_fix" -eq 0 ] || status=2
echo "(outputs in $out)"
exit "$status"
