#!/usr/bin/env bash
# A real Slurm run of the sharded sweep of docs/command-line.md, on this machine (issue 22).
#
# Installs Slurm and MUNGE from Debian's packages (when missing), starts a one-node cluster
# (munged + slurmctld + slurmd, node "localhost" with 2 CPUs, all state under $SLURM_SWEEP_DIR),
# submits that chapter's job array (`tensegrity sweep S.toml --jobs 2 --shard K/N --out
# shard-K.csv`), waits for it, merges the shards with `tensegrity merge`, and compares the merged
# CSV with the unsharded `tensegrity sweep` of the same scenario:
#   - the same header and the same rows (`index,grid_points` equal, row for row);
#   - `simulated_Q` and `error_Q` of every quantity Q the scenario checks equal within that
#     check's tolerance, on max(1, |a|, |b|) (a shard's continuation path may differ from the
#     unsharded one, src/sweep.rs; an angle may come out as pi or -pi), the other simulated
#     numbers (unchecked quantities, min_clearance_m) within the loosest check's tolerance,
#     `steps` (the path's length) only reported when the scenario continues from the previous
#     point, every other column (the grid's inputs,
#     analytic values, verdicts, branch, slack cables) equal as text.
# Prints the time of each phase. Stops the daemons it started (trap) and exits non-zero on any
# mismatch. Run as root; running it again starts from a clean state (idempotent).
#
#   bash benches/slurm_sweep.sh
#   SCENARIO=scenarios/mohr2011/workspace_grid_small.toml SHARDS=4 bash benches/slurm_sweep.sh
set -euo pipefail
cd "$(dirname "$0")/.."
REPO=$(pwd)

TENSEGRITY_BIN=${TENSEGRITY_BIN:-/root/.cache/tensegrity-testbed/target/release/tensegrity}
SCENARIO=${SCENARIO:-scenarios/mohr2011/workspace_sweep.toml}
SHARDS=${SHARDS:-16}
# Threads per array task (the chapter's `--jobs 2`); each task asks Slurm for as many CPUs.
JOBS=${JOBS:-2}
# The node's CPUs (this machine has 2).
NODE_CPUS=${NODE_CPUS:-2}
WORK=${SLURM_SWEEP_DIR:-/tmp/tensegrity-slurm}
# Seconds to wait for the node to come up and for the whole array to finish.
NODE_TIMEOUT_S=60
ARRAY_TIMEOUT_S=${ARRAY_TIMEOUT_S:-1800}
NODE=localhost
PACKAGES=(munge slurmctld slurmd slurm-client)

now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }
declare -A PHASE_S
PHASES=()
phase_done() { PHASE_S[$1]=$(elapsed "$2" "$(now)"); PHASES+=("$1"); echo "== $1: ${PHASE_S[$1]} s"; }

[ "$(id -u)" -eq 0 ] || { echo "run as root (apt-get, munged, slurmd)" >&2; exit 2; }
[ -f "$SCENARIO" ] || { echo "no scenario file $SCENARIO" >&2; exit 2; }
if [ ! -x "$TENSEGRITY_BIN" ]; then
  echo "building $TENSEGRITY_BIN"
  CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-/root/.cache/tensegrity-testbed/target} cargo build --release
  TENSEGRITY_BIN=${CARGO_TARGET_DIR:-/root/.cache/tensegrity-testbed/target}/release/tensegrity
fi

# --- daemons: only the ones this script started are stopped ---------------------------------
STARTED_PIDS=()
CREATED_POLICY=""
stop_daemons() {
  local pid
  for pid in "${STARTED_PIDS[@]}"; do
    kill "$pid" 2>/dev/null || true
  done
  for pid in "${STARTED_PIDS[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
  STARTED_PIDS=()
}
JOB=""
cleanup() {
  # Stopped early: cancel the array first (slurmd's job steps outlive slurmd).
  if [ -n "$JOB" ] && [ -n "$(squeue -h -j "$JOB" -o %i 2>/dev/null)" ]; then
    scancel "$JOB" || true
    for _ in $(seq 100); do [ -n "$(squeue -h -j "$JOB" -o %i 2>/dev/null)" ] || break; sleep 0.1; done
  fi
  stop_daemons
  [ -z "$CREATED_POLICY" ] || rm -f /usr/sbin/policy-rc.d
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# A previous run killed before its trap ran left its daemons (their pids are in $WORK/run).
for f in "$WORK"/run/*.pid; do
  [ -f "$f" ] || continue
  pid=$(cat "$f")
  if [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null && grep -qE 'munged|slurmctld|slurmd' "/proc/$pid/comm"; then
    echo "stopping $(cat "/proc/$pid/comm") $pid left by a previous run"
    STARTED_PIDS+=("$pid")
  fi
done
stop_daemons

# --- install ----------------------------------------------------------------------------------
t=$(now)
missing=()
for p in "${PACKAGES[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  # Debian's maintainer scripts would start the daemons with the packaged config: not here.
  if [ ! -e /usr/sbin/policy-rc.d ]; then
    printf '#!/bin/sh\nexit 101\n' >/usr/sbin/policy-rc.d; chmod +x /usr/sbin/policy-rc.d
    CREATED_POLICY=1
  fi
  apt-get update -q
  DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
fi
phase_done install "$t"
dpkg-query -W -f '${Package} ${Version}\n' "${PACKAGES[@]}"

# --- cluster ----------------------------------------------------------------------------------
t=$(now)
rm -rf "$WORK"
mkdir -p "$WORK"/{etc,run,log,state,spool,out}
chmod 0755 "$WORK" "$WORK"/*
MUNGE_SOCKET=$WORK/run/munge.socket
head -c 1024 /dev/urandom >"$WORK/etc/munge.key"
chmod 0400 "$WORK/etc/munge.key"
CONF=$WORK/etc/slurm.conf
cat >"$CONF" <<EOF
ClusterName=tensegrity
SlurmctldHost=$NODE
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$MUNGE_SOCKET
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/run/slurmctld.pid
SlurmdPidFile=$WORK/run/slurmd.pid
SlurmctldLogFile=$WORK/log/slurmctld.log
SlurmdLogFile=$WORK/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SchedulerType=sched/backfill
# Start the next array task as soon as one ends (the default waits up to 3 s between them).
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=$NODE_CPUS State=UNKNOWN
PartitionName=local Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$CONF

munged --force --foreground --socket="$MUNGE_SOCKET" --key-file="$WORK/etc/munge.key" \
  --pid-file="$WORK/run/munged.pid" --log-file="$WORK/log/munged.log" \
  --seed-file="$WORK/state/munged.seed" 2>>"$WORK/log/munged.out" &
STARTED_PIDS+=($!)
echo $! >"$WORK/run/munged.pid"
for _ in $(seq 50); do [ -S "$MUNGE_SOCKET" ] && break; sleep 0.1; done
munge --socket="$MUNGE_SOCKET" -n | unmunge --socket="$MUNGE_SOCKET" >/dev/null

slurmctld -D -c -f "$CONF" >"$WORK/log/slurmctld.out" 2>&1 &
STARTED_PIDS+=($!)
echo $! >"$WORK/run/slurmctld.pid"
slurmd -D -f "$CONF" -N "$NODE" >"$WORK/log/slurmd.out" 2>&1 &
STARTED_PIDS+=($!)
echo $! >"$WORK/run/slurmd.pid"
deadline=$(( $(date +%s) + NODE_TIMEOUT_S ))
until [ "$(sinfo -h -n "$NODE" -o %t 2>/dev/null)" = idle ]; do
  if [ "$(date +%s)" -ge "$deadline" ]; then
    echo "node $NODE not idle after ${NODE_TIMEOUT_S} s" >&2
    sinfo -N -l >&2 || true
    tail -n 20 "$WORK"/log/*.log >&2 || true
    exit 1
  fi
  sleep 0.5
done
sinfo -N -l
phase_done cluster "$t"

# --- docs/command-line.md's job array ---------------------------------------------------------
t=$(now)
OUT=$WORK/out
cat >"$WORK/shard.sbatch" <<EOF
#!/bin/bash
#SBATCH --array=1-$SHARDS
#SBATCH --cpus-per-task=$JOBS
#SBATCH --job-name=tensegrity-sweep
#SBATCH --output=$OUT/slurm-%A_%a.out
cd "$REPO"
"$TENSEGRITY_BIN" sweep "$SCENARIO" --jobs $JOBS --shard \${SLURM_ARRAY_TASK_ID}/$SHARDS --out "$OUT/shard-\${SLURM_ARRAY_TASK_ID}.csv"
rc=\$?
echo \$rc >"$OUT/rc-\${SLURM_ARRAY_TASK_ID}"
exit \$rc
EOF
# `sweep` exits 1 when a shard's points are out of tolerance or below the agreement: the CSV is
# still complete, so only the per-task codes below decide (0 or 1 is a run, anything else not).
# (`sbatch --wait` polls with a growing interval, up to half a minute late: poll squeue instead.)
JOB=$(sbatch --parsable "$WORK/shard.sbatch")
echo "submitted job array $JOB (tasks 1-$SHARDS)"
deadline=$(( $(date +%s) + ARRAY_TIMEOUT_S ))
while [ -n "$(squeue -h -j "$JOB" -o %i 2>/dev/null)" ]; do
  [ "$(date +%s)" -lt "$deadline" ] || { echo "array $JOB not done after ${ARRAY_TIMEOUT_S} s" >&2; exit 1; }
  sleep 0.5
done
JOB=""
bad=0
for k in $(seq "$SHARDS"); do
  rc=$(cat "$OUT/rc-$k" 2>/dev/null || echo missing)
  if [ "$rc" != 0 ] && [ "$rc" != 1 ]; then echo "array task $k: exit $rc" >&2; bad=1; fi
  [ -s "$OUT/shard-$k.csv" ] || { echo "array task $k wrote no CSV" >&2; bad=1; }
done
[ "$bad" -eq 0 ] || { tail -n 20 "$OUT"/slurm-*.out >&2 || true; exit 1; }
phase_done array "$t"

# --- merge ------------------------------------------------------------------------------------
t=$(now)
shard_csvs=()
for k in $(seq "$SHARDS"); do shard_csvs+=("$OUT/shard-$k.csv"); done
"$TENSEGRITY_BIN" merge "${shard_csvs[@]}" --out "$OUT/merged.csv"
phase_done merge "$t"

stop_daemons

# --- the unsharded sweep, and the comparison --------------------------------------------------
t=$(now)
set +e
"$TENSEGRITY_BIN" sweep "$SCENARIO" --jobs "$JOBS" --out "$OUT/unsharded.csv" | tail -n 3
rc=${PIPESTATUS[0]}
set -e
[ "$rc" -le 1 ] || { echo "unsharded sweep exited $rc" >&2; exit 1; }
phase_done unsharded "$t"

python3 - "$SCENARIO" "$OUT/unsharded.csv" "$OUT/merged.csv" <<'PY'
import csv, math, sys, tomllib
# Columns: index,grid_points, the grid's inputs, then analytic_/simulated_/error_ per quantity,
# then the verdict columns (settled, steps, within_tolerance, stable, branch, slack ...).
scenario, unsharded, merged = sys.argv[1:]
with open(scenario, "rb") as f:
    sc = tomllib.load(f)
tol = {c["quantity"]: float(c["tolerance"]) for c in sc.get("checks", [])}
continuation = sc.get("actuation", {}).get("continuation", False)
with open(unsharded, newline="") as f:
    a = list(csv.reader(f))
with open(merged, newline="") as f:
    b = list(csv.reader(f))
if a[0] != b[0]:
    sys.exit(f"headers differ:\n{a[0]}\n{b[0]}")
if len(a) != len(b):
    sys.exit(f"{len(a) - 1} unsharded rows, {len(b) - 1} merged")
header = a[0]
# With continuation the settle's step count depends on where it starts: reported only.
PATH_ONLY = {"steps"} if continuation else set()
# Unchecked simulated numbers (forces of unchecked quantities, clearance): the loosest check.
loosest = max(tol.values(), default=0.0)
def tolerance(name):
    for prefix in ("simulated_", "error_"):
        if name.startswith(prefix):
            return tol.get(name[len(prefix):], loosest)
    return loosest if name == "min_clearance_m" else None  # None: equal as text
def difference(x, y):
    """|x - y| on max(1, |x|, |y|); None when not numbers."""
    try:
        x, y = float(x), float(y)
    except ValueError:
        return None
    d = abs(x - y)
    # An angle at the wrap: pi and -pi are the same (its error column still has to agree).
    if abs(abs(x) - math.pi) <= 1e-6 and abs(abs(y) - math.pi) <= 1e-6:
        d = min(d, abs(abs(x) - abs(y)))
    return d / max(1.0, abs(x), abs(y))
identical, mismatches, steps_diff, worst = 0, [], 0, 0.0
for ra, rb in zip(a[1:], b[1:]):
    if ra[:2] != rb[:2]:
        sys.exit(f"row order differs: index,grid_points {ra[:2]} vs {rb[:2]}")
    identical += ra == rb
    for name, x, y in zip(header, ra, rb):
        if x == y:
            continue
        if name in PATH_ONLY:
            steps_diff = max(steps_diff, abs(int(x) - int(y)))
            continue
        t, d = tolerance(name), difference(x, y)
        if t is not None and d is not None and d <= t:
            worst = max(worst, d)
            continue
        mismatches.append(f"index {ra[0]} {name}: {x} vs {y}")
n = len(a) - 1
print(f"{n} rows, index 0..{n - 1} of {a[1][1]} in both; {identical} bit-identical; largest "
      f"difference within tolerance {worst:.3g}; steps differ by up to {steps_diff}; "
      f"{len(mismatches)} mismatch(es)")
if mismatches:
    print("\n".join(mismatches[:20]), file=sys.stderr)
    sys.exit(1)
PY

echo "== timings (s): $(for p in "${PHASES[@]}"; do printf '%s %s; ' "$p" "${PHASE_S[$p]}"; done)"
echo "merged CSV matches the unsharded sweep: $OUT/merged.csv"
