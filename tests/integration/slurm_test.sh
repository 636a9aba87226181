#!/usr/bin/env bash
# gibench study --slurm on a real one-node Slurm (Debian's slurm-wlm and
# munge), brought up by hand in a temporary directory: munged, slurmctld
# and slurmd in the background, a minimal slurm.conf (no cgroups, no
# accounting), stopped by PID when the test ends, whatever way it ends.
#   1. a tiny study run locally and through --slurm: the same run list and
#      metrics (the timings differ);
#   2. one method-run task cancelled on purpose: only its cell is marked
#      failed, with the task's Slurm state; the others are done;
#   3. resubmitting runs that cell alone and completes the study;
#   4. the reference stage cancelled: the report marks every run with the
#      reference task's fate;
#   5. one scene's reference task cancelled: that scene's runs alone are
#      marked (the other scene's runs are done).
# Before the cluster (no Slurm needed): --dry-run gives --gres to runs.sh
# only, never to the CPU-only references.
# Skipped ("SKIPPED: why") when not root or when the daemons cannot start.
# usage: slurm_test.sh GIBENCH ROOT OUT
set -u
GIB=$1 ROOT=$2 OUT=$3
skip() { echo "SKIPPED: $*"; exit 0; }
fail() { echo "FAIL: $*" >&2; exit 1; }

# --gres: the runs' script has it, the references' does not
dry=$(cd "$ROOT" && "$GIB" study tests/data/studies/slurm_tiny.json --out "$OUT/slurm_dry" --slurm --gres gpu:1 --dry-run 2>&1) ||
    fail "--dry-run failed: $dry"
refs_part=$(printf '%s\n' "$dry" | sed -n '/refs\.sh <==/,/<==/p')
runs_part=$(printf '%s\n' "$dry" | sed -n '/runs\.sh <==/,/<==/p')
printf '%s\n' "$runs_part" | grep -q '^#SBATCH --gres=gpu:1$' || fail "runs.sh lacks --gres: $dry"
printf '%s\n' "$refs_part" | grep -q -- '--gres' && fail "refs.sh (CPU only) has --gres: $refs_part"
echo "--gres: runs.sh only"

[ "$(id -u)" = 0 ] || skip "not running as root (munged, slurmctld and slurmd are started as root)"
for d in munged slurmctld slurmd sbatch squeue sinfo scontrol scancel python3; do
    command -v "$d" >/dev/null 2>&1 || [ -x "/usr/sbin/$d" ] || skip "$d is not installed (scripts/install-deps.sh installs slurm-wlm and munge)"
done
export PATH=$PATH:/usr/sbin

T=$(mktemp -d /tmp/gibench-slurm.XXXXXX) || fail "no temporary directory"
PIDS=()
cleanup() {
    local p e
    # the jobs first (their tasks end with their gibench processes) ...
    [ -n "${SLURM_CONF:-}" ] && scancel --full --quiet -u root 2>/dev/null
    # ... then the daemons, by PID ...
    for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null; done
    for p in "${PIDS[@]}"; do
        for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$p" 2>/dev/null
    done
    # ... and whatever they started that outlived them (slurmstepd, a task's
    # processes): the processes whose environment names this test's slurm.conf
    for e in /proc/[0-9]*/environ; do
        p=${e#/proc/}; p=${p%/environ}
        [ "$p" = $$ ] && continue
        if { tr '\0' '\n' < "$e"; } 2>/dev/null | grep -qx "SLURM_CONF=$T/slurm.conf"; then kill -9 "$p" 2>/dev/null; fi
    done
    rm -rf "$T"
}
trap cleanup EXIT
trap 'exit 1' INT TERM

host=$(hostname -s)
cpus=$(nproc)
port=$((20000 + $$ % 20000))
mkdir -p "$T/state" "$T/spool" "$T/munge"
chmod 700 "$T/munge"
head -c 1024 /dev/urandom > "$T/munge/munge.key"
chmod 400 "$T/munge/munge.key"
munged -F --force --key-file="$T/munge/munge.key" --socket="$T/munge/sock" --pid-file="$T/munge/pid" \
    --seed-file="$T/munge/seed" --log-file="$T/munge/log" >"$T/munged.out" 2>&1 &
PIDS+=($!)
for _ in $(seq 50); do [ -S "$T/munge/sock" ] && break; sleep 0.1; done
[ -S "$T/munge/sock" ] || skip "munged did not start: $(tail -n 3 "$T/munged.out" "$T/munge/log" 2>/dev/null | tr '\n' ' ')"

cat > "$T/slurm.conf" <<CONF
ClusterName=gibtest
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$T/munge/sock
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/slurmctld.log
SlurmdLogFile=$T/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
MinJobAge=600
KillWait=5
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=gibtest Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$T/slurm.conf
slurmctld -D -i -f "$T/slurm.conf" >"$T/slurmctld.out" 2>&1 &
PIDS+=($!)
slurmd -D -f "$T/slurm.conf" >"$T/slurmd.out" 2>&1 &
PIDS+=($!)
up=0
for _ in $(seq 100); do
    if sinfo -h -o %t 2>/dev/null | grep -Eq '^(idle|mix|alloc)'; then up=1; break; fi
    sleep 0.2
done
[ $up = 1 ] || skip "the one-node Slurm did not come up: $(tail -n 2 "$T/slurmctld.log" "$T/slurmd.log" 2>/dev/null | tr '\n' ' ')"
echo "slurm: one node $host, $cpus CPUs, up"

cd "$ROOT" || fail "no source tree $ROOT"
STUDY=tests/data/studies/slurm_tiny.json
L=$OUT/slurm_local S=$OUT/slurm_cluster F=$OUT/slurm_fault
rm -rf "$L" "$S" "$F"

# csv_same A B: the same runs, in the same order, with the same status and
# metrics (every column but the timings and what is derived from them)
csv_same() {
    python3 - "$1" "$2" <<'PY'
import csv, sys
a, b = (list(csv.DictReader(open(p))) for p in sys.argv[1:3])
keys = ["run", "scene", "method", "params", "status", "seed", "width", "height", "frames"]
keys += [k for k in a[0] if k.split("_")[0] in ("relmse", "rmse", "mae", "psnr", "ssim", "flip") or k.startswith("mean_lum_diff")]
if [r["run"] for r in a] != [r["run"] for r in b]:
    sys.exit("run lists differ: %s vs %s" % ([r["run"] for r in a], [r["run"] for r in b]))
for ra, rb in zip(a, b):
    for k in keys:
        if ra.get(k) != rb.get(k):
            sys.exit("%s: %s differs: %r vs %r" % (ra["run"], k, ra.get(k), rb.get(k)))
print("%d runs, %d columns compared, identical" % (len(a), len(keys)))
PY
}
now() { date +%s.%N; }

# 1. locally, then on the cluster
t0=$(now)
"$GIB" study "$STUDY" --out "$L" >"$T/local.out" 2>&1 || fail "the local study failed: $(tail -n 3 "$T/local.out")"
t1=$(now)
"$GIB" study "$STUDY" --out "$S" --slurm --time 5 --array-limit 2 >"$T/slurm.out" 2>&1 ||
    fail "the study through --slurm failed: $(tail -n 5 "$T/slurm.out")"
t2=$(now)
grep -q "submitted: references [0-9]* (1 tasks), runs [0-9]* (3 tasks), collect [0-9]*" "$T/slurm.out" ||
    fail "--slurm did not submit 1 reference and 3 run tasks: $(cat "$T/slurm.out")"
[ -s "$S/report.md" ] || fail "the collect job wrote no report"
same=$(csv_same "$L/runs.csv" "$S/runs.csv") || fail "local and Slurm results differ: $same"
ls "$S"/slurm/logs/run-*_0.log >/dev/null 2>&1 || fail "no task log in $S/slurm/logs"
awk -v s="$same" -v a="$t0" -v b="$t1" -v c="$t2" \
    'BEGIN { printf "local vs slurm: %s; wall %.1f s locally, %.1f s through Slurm (submission to report)\n", s, b - a, c - b }'

# resubmitting a finished study runs nothing but the collect job
"$GIB" study "$STUDY" --out "$S" --slurm >"$T/again.out" 2>&1 || fail "resubmitting a done study failed: $(tail -n 3 "$T/again.out")"
grep -q "(0 to make), 3 runs (3 done before, 0 not applicable, 0 to run)" "$T/again.out" ||
    fail "a done study was not taken as done: $(cat "$T/again.out")"

# 2. one method-run task cancelled while it waits for the references
victim=$("$GIB" study "$STUDY" --dry-run 2>/dev/null | sed -n 's/^run \([^:]*\):.*/\1/p' | sed -n 2p)
[ -n "$victim" ] || fail "no second run in the plan"
"$GIB" study "$STUDY" --out "$F" --slurm --no-wait >"$T/fault.out" 2>&1 || fail "--no-wait failed: $(cat "$T/fault.out")"
read -r runs_job collect_job < <(sed -n 's/^submitted: .*runs \([0-9]*\) .*collect \([0-9]*\)$/\1 \2/p' "$T/fault.out")
[ -n "${collect_job:-}" ] || fail "--no-wait printed no job ids: $(cat "$T/fault.out")"
scancel "${runs_job}_1" || fail "scancel ${runs_job}_1 failed"
for _ in $(seq 300); do
    st=$(squeue -h -t all -j "$collect_job" -o %T 2>/dev/null)
    case "$st" in PENDING|RUNNING|CONFIGURING|COMPLETING) sleep 0.5 ;; *) break ;; esac
done
[ "$st" = COMPLETED ] || fail "the collect job ended $st: $(tail -n 3 "$F"/slurm/logs/collect-*.log)"
python3 - "$F/runs.csv" "$victim" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
bad = [r for r in rows if r["status"] != "ok"]
assert len(rows) == 3, rows
assert [r["run"] for r in bad] == [sys.argv[2]], [(r["run"], r["status"], r["reason"]) for r in bad]
reason = bad[0]["reason"]
assert "CANCELLED" in reason and "_1:" in reason, reason
print("marked:", bad[0]["run"], "-", reason)
PY
[ $? = 0 ] || { scontrol -o show job "$runs_job"; sacct -n -P -X -j "$runs_job"; fail "the cancelled task's cell is not the only one marked"; }

# 3. resubmitting runs that cell alone (and times the path tracer's curve
# again with it); the other two runs were timed by the first submission, so
# the report mixes two clocks: only with --mix-clocks, and it says so
# (docs/studies.md, "One clock per comparison")
"$GIB" study "$STUDY" --out "$F" --slurm --mix-clocks >"$T/resume.out" 2>&1 || fail "resubmitting failed: $(tail -n 3 "$T/resume.out")"
grep -q "(0 to make), 3 runs (2 done before, 0 not applicable, 1 to run)" "$T/resume.out" ||
    fail "resubmitting did not run the one missing cell alone: $(cat "$T/resume.out")"
grep -q "curves are timed again with the runs" "$T/resume.out" ||
    fail "resubmitting did not time the curve again with the run: $(cat "$T/resume.out")"
grep -q "Clocks are mixed" "$F/report.md" || fail "the resubmitted study's report does not say its clocks are mixed"
same=$(csv_same "$L/runs.csv" "$F/runs.csv") || fail "after resubmitting, results differ from the local run: $same"
echo "resubmitted: $same"
# 4. the reference stage cancelled: the collect job still reports, every
# run marked with the reference task's fate
R=$OUT/slurm_noref
rm -rf "$R"
"$GIB" study "$STUDY" --out "$R" --slurm --no-wait >"$T/noref.out" 2>&1 || fail "--no-wait failed: $(cat "$T/noref.out")"
read -r refs_job collect_job < <(sed -n 's/^submitted: references \([0-9]*\) .*collect \([0-9]*\)$/\1 \2/p' "$T/noref.out")
[ -n "${collect_job:-}" ] || fail "--no-wait printed no job ids: $(cat "$T/noref.out")"
scancel "$refs_job" || fail "scancel $refs_job failed"
for _ in $(seq 300); do
    st=$(squeue -h -t all -j "$collect_job" -o %T 2>/dev/null)
    case "$st" in PENDING|RUNNING|CONFIGURING|COMPLETING) sleep 0.5 ;; *) break ;; esac
done
[ "$st" = COMPLETED ] || fail "the collect job ended $st after the references were cancelled"
python3 - "$R/runs.csv" "$refs_job" <<'PY' || fail "runs without their references are not marked so"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert len(rows) == 3, rows
for r in rows:
    assert r["status"] == "failed" and r["reason"].startswith("no reference") and \
        ("Slurm task %s_0: CANCELLED" % sys.argv[2]) in r["reason"], (r["run"], r["status"], r["reason"])
print("no references:", rows[0]["reason"])
PY
# 5. two scenes, the references one at a time (--array-limit 1), the first
# slow enough (spp 2048) that the second is still pending when cancelled:
# only the second scene's runs fail
P=$OUT/slurm_onescene
rm -rf "$P"
cat > "$T/two.json" <<JSON
{"name": "slurm_two", "base": "$ROOT", "scenes": ["scenes/cornell_box_coarse.gltf", "scenes/bunny_env.glb"],
 "size": [16, 16], "frames": 1, "warmup": 0, "timeout": 60,
 "methods": [{"method": "direct"}], "reference": {"spp": 2048, "max_bounces": 2}}
JSON
"$GIB" study "$T/two.json" --out "$P" --slurm --no-wait --array-limit 1 >"$T/two.out" 2>&1 || fail "--no-wait failed: $(cat "$T/two.out")"
read -r refs_job collect_job < <(sed -n 's/^submitted: references \([0-9]*\) .*collect \([0-9]*\)$/\1 \2/p' "$T/two.out")
[ -n "${collect_job:-}" ] || fail "--no-wait printed no job ids: $(cat "$T/two.out")"
scancel "${refs_job}_1" || fail "scancel ${refs_job}_1 failed"
for _ in $(seq 300); do
    st=$(squeue -h -t all -j "$collect_job" -o %T 2>/dev/null)
    case "$st" in PENDING|RUNNING|CONFIGURING|COMPLETING) sleep 0.5 ;; *) break ;; esac
done
[ "$st" = COMPLETED ] || fail "the collect job ended $st after one reference was cancelled"
python3 - "$P/runs.csv" "$refs_job" <<'PY' || fail "one failed reference did not cost its scene's runs alone"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert len(rows) == 2, rows
by = {r["scene"].split("/")[-1]: r for r in rows}
ok, bad = by["cornell_box_coarse.gltf"], by["bunny_env.glb"]
assert ok["status"] == "ok", (ok["run"], ok["status"], ok["reason"])
assert bad["status"] == "failed" and bad["reason"].startswith("no reference") and \
    ("Slurm task %s_1: CANCELLED" % sys.argv[2]) in bad["reason"], (bad["run"], bad["status"], bad["reason"])
print("one reference cancelled:", bad["run"], "-", bad["reason"])
PY
echo "slurm: all checks passed"
