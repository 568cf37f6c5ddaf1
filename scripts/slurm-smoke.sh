#!/usr/bin/env bash
# Slurm smoke test of the evaluation's cluster path (docs/evaluation-cluster.md).
#
# Starts a one-node Slurm cluster on this machine from Debian's packages
# (slurm-wlm, munge) with its own configuration in a scratch folder (no
# systemd: munged, slurmctld and slurmd are started here and stopped on exit),
# renders a three-run dataset, runs `shadyloc eval --plan`, submits the map
# jobs and then the pair jobs (afterok dependency) as two job arrays, merges,
# runs the same evaluation locally and checks that every output file is
# byte-identical, except wall times (timing.json, *_timing.json).
#
#   scripts/slurm-smoke.sh [--shadyloc PATH] [--frames N] [-c CONFIG]... [--keep]
#
#   --shadyloc PATH  the shadyloc program (default: build/shadyloc)
#   --frames N       frames per rendered run (default 12)
#   -c CONFIG        settings for every `shadyloc eval` (repeatable; default
#                    config/vo_sim.ini and config/localise_sim.ini, the
#                    simulator's camera)
#   --keep           keep the scratch folder (configs, daemon logs, outputs)
#
# Needs root (the daemons run as root with SlurmUser=root). Exit codes:
# 0 passed, 77 skipped (not root, slurm-wlm / munge missing: scripts/setup.sh
# installs them, or the daemons cannot run in this container: their log is
# printed), anything else failed (the message names the step).
# SHADYLOC_SLURM_TIMEOUT (s, default 900) bounds the wait for the jobs, so the
# daemons are always stopped here before an outer timeout could kill us.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

shadyloc="$here/build/shadyloc"
frames=12
keep=0
eval_cfg=()
while [ $# -gt 0 ]; do
	case "$1" in
	--shadyloc) shadyloc="$2"; shift 2 ;;
	--frames) frames="$2"; shift 2 ;;
	-c | --config) eval_cfg+=(-c "$(cd "$(dirname "$2")" && pwd)/$(basename "$2")"); shift 2 ;;
	--keep) keep=1; shift ;;
	-h | --help) sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0"; exit 0 ;;
	*) echo "slurm-smoke: unknown argument '$1' (see --help)" >&2; exit 2 ;;
	esac
done
job_timeout="${SHADYLOC_SLURM_TIMEOUT:-900}"
[ ${#eval_cfg[@]} -gt 0 ] || eval_cfg=(-c "$here/config/vo_sim.ini" -c "$here/config/localise_sim.ini")

say() { echo "[slurm-smoke] $*"; }
skip() { echo "[slurm-smoke] SKIPPED: $*"; exit 77; }

# ---- preconditions: skip where this machine cannot run the test ------------
# The daemons live in /usr/sbin, not on every root PATH (sudo, CI shells).
PATH="$PATH:/usr/sbin:/sbin"
[ "$(id -u)" -eq 0 ] || skip "needs root (munged, slurmctld and slurmd run as root with their own configuration)"
missing=()
for c in munged mungekey slurmctld slurmd sbatch squeue sinfo scontrol scancel; do
	command -v "$c" >/dev/null 2>&1 || missing+=("$c")
done
[ ${#missing[@]} -eq 0 ] || skip "missing ${missing[*]}: install Debian's slurm-wlm and munge (scripts/setup.sh does)"
if [ ! -x "$shadyloc" ]; then
	echo "[slurm-smoke] FAILED: no shadyloc program at $shadyloc (build first: scripts/setup.sh, or pass --shadyloc)" >&2
	exit 1
fi
shadyloc="$(cd "$(dirname "$shadyloc")" && pwd)/$(basename "$shadyloc")"
if ! "$shadyloc" eval --help >/dev/null 2>&1; then
	echo "[slurm-smoke] FAILED: '$shadyloc eval --help' does not run: this shadyloc has no eval command" >&2
	exit 1
fi

# An outer Slurm job's variables would steer our sbatch/squeue; only ours count.
while IFS='=' read -r name _; do
	case "$name" in SLURM_* | SBATCH_* | SQUEUE_* | SINFO_* | SCONTROL_*) unset "$name" ;; esac
done < <(env)

# ---- steps, failure reporting and cleanup -----------------------------------
step=""
step_t0=$(date +%s)
t_start=$step_t0
timings=()
begin() {
	local now; now=$(date +%s)
	[ -z "$step" ] || timings+=("$(printf '%-30s %4d s' "$step" $((now - step_t0)))")
	step="$1"; step_t0=$now
	say "== $step"
}
reported=0
fail() { echo "[slurm-smoke] FAILED in step '$step': $*" >&2; reported=1; exit 1; }
# The cluster itself not coming up (munged, slurmctld, slurmd in this
# container) says nothing about shadyloc: reported loudly as a skip, with the
# daemon's log; every step after the node is idle fails for real.
cannot_host() {
	echo "[slurm-smoke] SKIPPED: this machine cannot host a one-node Slurm cluster: $* (step '$step')" >&2
	reported=1; exit 77
}

work="$(mktemp -d "${TMPDIR:-/tmp}/shadyloc-slurm.XXXXXX")"
# munged wants its socket's folder (and those above it) searchable by all.
chmod 755 "$work"
mkdir -p "$work/munge-key" "$work/munge" "$work/state" "$work/spool" "$work/log" "$work/joblogs"
chmod 700 "$work/munge-key"

pid_munged="" pid_ctld="" pid_slurmd=""
job_ids=()

stop_pid() {  # stop_pid PID NAME: TERM, up to 10 s, then KILL
	local pid="$1"
	[ -n "$pid" ] && kill -0 "$pid" 2>/dev/null || return 0
	kill -TERM "$pid" 2>/dev/null || true
	for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
	if kill -0 "$pid" 2>/dev/null; then
		say "$2 (pid $pid) did not stop on TERM; killing it"
		kill -KILL "$pid" 2>/dev/null || true
	fi
	wait "$pid" 2>/dev/null || true
}

show_logs() {
	local f logs=("$work/log/slurmctld.log" "$work/log/slurmd.log")
	[ -z "$pid_munged" ] || kill -0 "$pid_munged" 2>/dev/null || logs+=("$work/log/munged.out")
	for f in "${logs[@]}" "$work"/joblogs/*.out; do
		[ -s "$f" ] || continue
		echo "----- last lines of $f"
		tail -n 12 "$f"
	done
}

cleanup() {
	local rc=$?
	trap - EXIT INT TERM
	set +e
	if [ $rc -ne 0 ] && [ $rc -ne 77 ]; then
		[ "$reported" = 1 ] || echo "[slurm-smoke] FAILED (exit $rc) in step '$step'" >&2
		case "$step" in start* | submit*) show_logs >&2 ;; esac
	fi
	if [ ${#job_ids[@]} -gt 0 ] && [ -n "$pid_ctld" ] && kill -0 "$pid_ctld" 2>/dev/null; then
		local ids; ids=$(IFS=,; echo "${job_ids[*]}")
		if [ -n "$(squeue -h -j "$ids" -o %i 2>/dev/null)" ]; then
			say "cancelling jobs $ids"
			scancel "${job_ids[@]}" 2>/dev/null
			for _ in $(seq 50); do [ -z "$(squeue -h -j "$ids" -o %i 2>/dev/null)" ] && break; sleep 0.2; done
		fi
	fi
	stop_pid "$pid_slurmd" slurmd
	stop_pid "$pid_ctld" slurmctld
	stop_pid "$pid_munged" munged
	if [ "$keep" = 1 ]; then
		say "kept $work"
	else
		rm -rf "$work"
	fi
	exit $rc
}
trap cleanup EXIT
trap 'echo "[slurm-smoke] interrupted (SIGINT)" >&2; reported=1; exit 130' INT
trap 'echo "[slurm-smoke] interrupted (SIGTERM)" >&2; reported=1; exit 143' TERM

# ---- munge ------------------------------------------------------------------
begin "start munged"
mungekey --create --keyfile="$work/munge-key/munge.key" >/dev/null 2>&1 \
	|| cannot_host "mungekey could not create $work/munge-key/munge.key"
socket="$work/munge/munge.socket"
munged --foreground --key-file="$work/munge-key/munge.key" --socket="$socket" \
	--pid-file="$work/munge/munged.pid" --seed-file="$work/munge/munged.seed" \
	--log-file="$work/log/munged.log" >"$work/log/munged.out" 2>&1 &
pid_munged=$!
for _ in $(seq 50); do [ -S "$socket" ] && break; kill -0 "$pid_munged" 2>/dev/null || break; sleep 0.1; done
[ -S "$socket" ] || { cat "$work/log/munged.out" "$work/log/munged.log" >&2 2>/dev/null; cannot_host "munged did not create its socket"; }
munge --socket="$socket" --no-input | unmunge --socket="$socket" >/dev/null \
	|| cannot_host "a munge credential does not decode with our munged"

# ---- slurm.conf for one node ------------------------------------------------
begin "configure slurm"
# slurmd's own view of the node (name and CPU layout) avoids a node that
# registers as invalid because the configuration disagrees with the hardware.
hw="$(slurmd -C 2>/dev/null | head -n 1)" || true
node="$(sed -n 's/^NodeName=\([^ ]*\).*/\1/p' <<<"$hw")"
[ -n "$node" ] || node="$(uname -n | cut -d. -f1)"
layout="$(grep -o -E '(CPUs|Boards|SocketsPerBoard|CoresPerSocket|ThreadsPerCore)=[0-9]+' <<<"$hw" | paste -s -d ' ')"
[ -n "$layout" ] || layout="CPUs=$(nproc)"

# Two free TCP ports (the default 6817/6818 may belong to a real cluster).
port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
ctld_port="" slurmd_port=""
for ((p = 20000 + ($$ % 20000) * 2, n = 0; n < 200; p += 2, n++)); do
	[ $p -lt 65000 ] || p=20000
	if port_free $p && port_free $((p + 1)); then ctld_port=$p; slurmd_port=$((p + 1)); break; fi
done
[ -n "$ctld_port" ] || fail "no two free TCP ports found on 127.0.0.1"

export SLURM_CONF="$work/slurm.conf"
cat >"$SLURM_CONF" <<EOF
# One-node cluster of scripts/slurm-smoke.sh (scratch configuration).
ClusterName=shadyloc-smoke
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
# No cgroups and no systemd: processes are tracked through /proc, tasks unbound.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
MailProg=/bin/true
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
# The node is what this file says, whatever the container reports.
SlurmdParameters=config_overrides
ReturnToService=2
# Finished jobs stay visible to scontrol long enough for the checks below.
MinJobAge=3600
NodeName=$node NodeAddr=127.0.0.1 $layout RealMemory=1000 State=UNKNOWN
PartitionName=smoke Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
# slurmd reads cgroup.conf beside slurm.conf even when no plugin uses cgroups;
# on a cgroup v2 host without systemd it must not ask systemd over D-Bus.
cat >"$work/cgroup.conf" <<EOF
CgroupPlugin=autodetect
IgnoreSystemd=yes
EOF
say "node $node ($layout), slurmctld port $ctld_port, slurmd port $slurmd_port, config $SLURM_CONF"

# ---- daemons ----------------------------------------------------------------
begin "start slurmctld and slurmd"
slurmctld -D -c -f "$SLURM_CONF" >"$work/log/slurmctld.out" 2>&1 &
pid_ctld=$!
slurmd -D -f "$SLURM_CONF" >"$work/log/slurmd.out" 2>&1 &
pid_slurmd=$!
state=""
for _ in $(seq 120); do
	kill -0 "$pid_ctld" 2>/dev/null || { tail -n 20 "$work/log/slurmctld.out" >&2; cannot_host "slurmctld exited (its log above)"; }
	kill -0 "$pid_slurmd" 2>/dev/null || { tail -n 20 "$work/log/slurmd.out" >&2; cannot_host "slurmd exited (its log above)"; }
	state="$(sinfo -h -n "$node" -o %T 2>/dev/null || true)"
	[ "$state" = idle ] && break
	sleep 0.5
done
[ "$state" = idle ] || { tail -n 20 "$work/log/slurmctld.out" "$work/log/slurmd.out" >&2; cannot_host "node $node is '${state:-unknown}', not idle, after 60 s"; }
say "node $node is idle"

# ---- a three-run dataset ----------------------------------------------------
begin "render the dataset"
# The first three of the simulator's default traversals.
traversals="$(sed -n 's/^[[:space:]]*traversals[[:space:]]*=[[:space:]]*\([^;#]*\).*/\1/p' "$here/config/sim.ini" | head -n 1)"
read -r -a trav <<<"$traversals"
[ ${#trav[@]} -ge 3 ] || fail "config/sim.ini lists fewer than three default traversals ('$traversals')"
trav=("${trav[@]:0:3}")
"$shadyloc" sim -q -c "$here/config/sim.ini" -o "$work/data" --frames "$frames" \
	--traversals "$(IFS=,; echo "${trav[*]}")" || fail "shadyloc sim failed"
{
	echo "# run rawlog ground_truth (paths relative to this file)"
	for t in "${trav[@]}"; do echo "$t $t.rawlog $t.tum"; done
} >"$work/data/runs.txt"
say "runs: ${trav[*]} ($frames frames each)"

# ---- plan -------------------------------------------------------------------
begin "eval --plan"
runs="$work/data/runs.txt"
cluster="$work/cluster"
say "settings: ${eval_cfg[*]}"
plan="$("$shadyloc" eval --runs "$runs" -o "$cluster" "${eval_cfg[@]}" --plan)" || fail "shadyloc eval --plan failed"
echo "$plan" | sed 's/^/  /'
read -r _ map_first map_last < <(grep -E '^maps [0-9]+ [0-9]+$' <<<"$plan") || true
read -r _ pair_first pair_last < <(grep -E '^pairs [0-9]+ [0-9]+$' <<<"$plan") || true
[ -n "${map_last:-}" ] && [ -n "${pair_last:-}" ] \
	|| fail "--plan did not print 'maps FIRST LAST' and 'pairs FIRST LAST'"
[ "$map_first" -eq 0 ] && [ "$pair_first" -eq $((map_last + 1)) ] && [ "$pair_last" -ge "$pair_first" ] \
	|| fail "unexpected job ranges: maps $map_first-$map_last, pairs $pair_first-$pair_last"
[ -f "$cluster/plan.tsv" ] || fail "--plan wrote no $cluster/plan.tsv"

# ---- the two job arrays -----------------------------------------------------
begin "submit and run the job arrays"
# One job = one `shadyloc eval --job K`; the array index is K.
cat >"$work/eval-job.sh" <<EOF
#!/bin/bash
exec $(printf '%q' "$shadyloc") eval --runs $(printf '%q' "$runs") -o $(printf '%q' "$cluster") $(printf '%q ' "${eval_cfg[@]}")-q --job "\$SLURM_ARRAY_TASK_ID"
EOF
chmod +x "$work/eval-job.sh"
submit() {  # submit NAME RANGE [sbatch options...] -> prints the job id
	local name="$1" range="$2"; shift 2
	local out
	out="$(sbatch --parsable --job-name="shadyloc-$name" --array="$range" --cpus-per-task=1 \
		--chdir="$work" --output="$work/joblogs/${name}_%a.out" "$@" "$work/eval-job.sh")" \
		|| fail "sbatch of the $name array failed"
	echo "${out%%;*}"
}
maps_id="$(submit maps "$map_first-$map_last")"
job_ids+=("$maps_id")
pairs_id="$(submit pairs "$pair_first-$pair_last" --dependency="afterok:$maps_id" --kill-on-invalid-dep=yes)"
job_ids+=("$pairs_id")
say "maps: job $maps_id (array $map_first-$map_last); pairs: job $pairs_id (array $pair_first-$pair_last, after the maps)"

deadline=$(($(date +%s) + job_timeout))
last_report=0
while :; do
	queue="$(squeue -h -r -j "$maps_id,$pairs_id" -o '%i %T' 2>/dev/null)" || fail "squeue failed"
	[ -n "$queue" ] || break
	now=$(date +%s)
	[ "$now" -lt "$deadline" ] || fail "jobs not finished after $job_timeout s (SHADYLOC_SLURM_TIMEOUT): $(tr '\n' ' ' <<<"$queue")"
	if [ $((now - last_report)) -ge 10 ]; then
		say "  $(grep -c RUNNING <<<"$queue" || true) running, $(grep -c PENDING <<<"$queue" || true) pending"
		last_report=$now
	fi
	sleep 1
done

check_array() {  # check_array ID NAME: every task COMPLETED with exit 0
	local id="$1" name="$2" line task st reason code bad=0
	while read -r line; do
		[ -n "$line" ] || continue
		task="$(sed -n 's/.* ArrayTaskId=\([^ ]*\).*/\1/p' <<<"$line")"
		st="$(sed -n 's/.* JobState=\([^ ]*\).*/\1/p' <<<"$line")"
		reason="$(sed -n 's/.* Reason=\([^ ]*\).*/\1/p' <<<"$line")"
		code="$(sed -n 's/.* ExitCode=\([^ ]*\).*/\1/p' <<<"$line")"
		if [ "$st" != COMPLETED ] || [ "$code" != 0:0 ]; then
			echo "[slurm-smoke]   $name task $task: $st ($reason), exit $code" >&2
			bad=1
		fi
	done < <(scontrol -o show job "$id")
	return $bad
}
arrays_ok=1
check_array "$maps_id" maps || arrays_ok=0
check_array "$pairs_id" pairs || arrays_ok=0
[ $arrays_ok -eq 1 ] || fail "not every job completed (job logs below)"
say "all $((pair_last + 1)) jobs completed"

# ---- merge, local run, comparison --------------------------------------------
begin "eval --merge"
"$shadyloc" eval --runs "$runs" -o "$cluster" "${eval_cfg[@]}" -q --merge >"$work/log/merge.out" 2>&1 \
	|| { tail -n 20 "$work/log/merge.out" >&2; fail "shadyloc eval --merge failed"; }

begin "local eval"
"$shadyloc" eval --runs "$runs" -o "$work/local" "${eval_cfg[@]}" -q -j 2 >"$work/log/local.out" 2>&1 \
	|| { tail -n 20 "$work/log/local.out" >&2; fail "local shadyloc eval failed"; }

begin "compare outputs"
for f in table1.md table1.csv eval.json; do
	[ -f "$cluster/$f" ] || fail "the merged output has no $f"
	[ -f "$work/local/$f" ] || fail "the local output has no $f"
done
compared=0
differ=()
while IFS= read -r -d '' f; do
	rel="${f#"$work/local/"}"
	case "$(basename "$rel")" in timing.json | *_timing.json) continue ;; esac
	if [ ! -f "$cluster/$rel" ]; then
		differ+=("$rel (only in the local run)")
	elif ! cmp -s "$f" "$cluster/$rel"; then
		differ+=("$rel (differs: $(cmp "$f" "$cluster/$rel" 2>&1 | sed 's/.*: //' || true))")
	fi
	compared=$((compared + 1))
done < <(find "$work/local" -type f -print0 | sort -z)
# The cluster run's own bookkeeping (the plan and per-job results) aside, it
# must not have produced anything the local run did not.
while IFS= read -r -d '' f; do
	rel="${f#"$cluster/"}"
	case "$rel" in plan.tsv | jobs/* | timing.json | */timing.json | *_timing.json) continue ;; esac
	[ -e "$work/local/$rel" ] || differ+=("$rel (only in the merged run)")
done < <(find "$cluster" -type f -print0 | sort -z)
if [ ${#differ[@]} -gt 0 ]; then
	printf '[slurm-smoke]   %s\n' "${differ[@]}" >&2
	fail "merged and local outputs differ in ${#differ[@]} file(s)"
fi
say "$compared output files byte-identical (wall times in timing.json and *_timing.json aside), among them:"
for f in table1.md table1.csv eval.json; do say "  $f $(wc -c <"$cluster/$f") bytes"; done

begin "done"
say "timings:"
printf '[slurm-smoke]   %s\n' "${timings[@]}"
say "total $(($(date +%s) - t_start)) s"
say "PASSED"
