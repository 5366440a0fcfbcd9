#!/bin/bash
# A single-node Slurm cluster on 127.0.0.1, started and stopped by this test: munge with its own key and socket,
# slurmctld and slurmd with their own config, ports, spool, state and log folders in a temporary directory
# (proctrack/linuxproc, task/none, select/cons_tres). `hovs slurm submit --shards 8 --wait` renders a dataset as
# an 8-task array and merges it; the result must be the set one process writes (images and ground truth byte for
# byte, the manifest apart from render timings). Bad submissions end in one clear error. Every daemon is stopped
# by its PID. Where the machine refuses the daemons (not root, Slurm or munge missing, a daemon that does not
# come up) the test reports SKIPPED (exit 77) with the reason, never a silent pass.
# Usage: slurm_cluster_test.sh HOVS_BINARY SOURCE_DIR
set -u
hovs=$(readlink -f "$1")
src=$(readlink -f "$2")
skip() {
  echo "SKIPPED: $*" >&2
  exit 77
}
[ "$(id -u)" -eq 0 ] || skip "slurmctld and slurmd run as root here (SlurmUser=root); this test runs as $(id -un)"
for p in munged mungekey slurmctld slurmd sbatch squeue scontrol sinfo python3; do
  command -v "$p" > /dev/null || skip "$p is not installed (scripts/setup.sh installs slurm-wlm and munge)"
done

dir=$(mktemp -d /tmp/hovs-slurm.XXXXXX)
chmod 755 "$dir"  # munged wants its socket's folder reachable by all
pids=()
stop_all() {
  for f in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munged.pid"; do
    if [ -s "$f" ]; then
      pid=$(cat "$f")
      kill "$pid" 2> /dev/null
      for _ in $(seq 50); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
      kill -9 "$pid" 2> /dev/null
    fi
  done
  rm -rf "$dir"
}
trap stop_all EXIT
fail() {
  echo "FAILED: $*" >&2
  for f in "$dir"/*.log; do [ -f "$f" ] && { echo "--- $f" >&2; tail -20 "$f" >&2; }; done
  exit 1
}

# Two free TCP ports on 127.0.0.1 for slurmctld and slurmd.
read -r ctld_port slurmd_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')

mkdir -p "$dir/state" "$dir/spool"
host=$(hostname -s)  # slurmctld serves only on the host SlurmctldHost names
mungekey -c -k "$dir/munge.key" 2> "$dir/mungekey.log" || skip "mungekey cannot create a key: $(cat "$dir/mungekey.log")"
chmod 600 "$dir/munge.key"
munged --force --key-file="$dir/munge.key" --socket="$dir/munge.sock" --pid-file="$dir/munged.pid" \
  --log-file="$dir/munged.log" --seed-file="$dir/munge.seed" 2> "$dir/munged.err" ||
  skip "munged does not start: $(cat "$dir/munged.err")"

cat > "$dir/slurm.conf" << EOF
ClusterName=hovstest
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
AuthInfo=socket=$dir/munge.sock
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
ReturnToService=2
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
NodeName=hovsnode NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=hovs Nodes=hovsnode Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$dir/slurm.conf
slurmctld -f "$SLURM_CONF" -i 2> "$dir/slurmctld.err" || skip "slurmctld does not start: $(cat "$dir/slurmctld.err")"
slurmd -f "$SLURM_CONF" -N hovsnode 2> "$dir/slurmd.err" || skip "slurmd does not start: $(cat "$dir/slurmd.err")"
up=0
for _ in $(seq 60); do
  kill -0 "$(cat "$dir/slurmctld.pid" 2> /dev/null)" 2> /dev/null ||
    skip "slurmctld stopped: $(grep -m1 error "$dir/slurmctld.log" 2> /dev/null)"
  if timeout 2 sinfo -h -o %t 2> /dev/null | grep -q idle; then up=1; break; fi
  sleep 0.3
done
[ $up -eq 1 ] || skip "the node does not come up idle: $(sinfo 2>&1 | tail -2); $(tail -3 "$dir/slurmd.log" 2> /dev/null)"

cd "$dir" || exit 1
dataset=(dataset --scene "$src/scenes/reference_calibration.yaml" -n 8 --seed 3 --downscale 10 --samples 1)
"$hovs" -q slurm submit --shards 8 --array-throttle 4 --wait --poll 0.5 --timeout 600 -- "${dataset[@]}" \
  --out "$dir/merged" > "$dir/submit.out" 2>&1 || fail "hovs slurm submit: $(cat "$dir/submit.out")"
"$hovs" -q "${dataset[@]}" --out "$dir/single" > "$dir/single.out" 2>&1 || fail "single run: $(cat "$dir/single.out")"

# The job folder: a readable script, the record, a log per task.
grep -q '^#SBATCH --array=0-7%4$' "$dir/merged.slurm/job.sbatch" || fail "job.sbatch: no array line"
[ "$(ls "$dir/merged.slurm/logs" | wc -l)" -eq 8 ] || fail "expected 8 task logs"
"$hovs" --json slurm status "$dir/merged.slurm" > "$dir/status.json" 2>&1 || fail "status: $(cat "$dir/status.json")"
python3 - "$dir" << 'EOF' || fail "the merged set differs from the single-process set"
import json, pathlib, sys
d = pathlib.Path(sys.argv[1])
status = json.loads((d / "status.json").read_text())
assert len(status["tasks"]) == 8 and all(t["output_complete"] for t in status["tasks"]), status
def manifest(p):
    m = json.loads((p / "dataset.json").read_text())
    for f in m["frames"]:
        f.pop("render_seconds", None)
    return m
a, b = manifest(d / "single"), manifest(d / "merged")
assert a == b, "manifests differ"
files = 0
for f in a["frames"]:
    for v in f["views"]:
        for rel in (v["image"], v["ground_truth"]["exr"], v["ground_truth"]["sidecar"]):
            assert (d / "single" / rel).read_bytes() == (d / "merged" / rel).read_bytes(), rel
            files += 1
assert files == 24, files
print("merged == single:", files, "files")
EOF

# The tolerance study as a 4-task array: merged, the same files as one process.
tolerance=(tolerance -c "$src/study/reference.yaml" -n 200)
"$hovs" -q slurm submit --shards 4 --wait --poll 0.5 --timeout 300 -- "${tolerance[@]}" --out "$dir/tol-merged" \
  > "$dir/tol-submit.out" 2>&1 || fail "hovs slurm submit tolerance: $(cat "$dir/tol-submit.out")"
"$hovs" -q "${tolerance[@]}" --out "$dir/tol-single" > "$dir/tol-single.out" 2>&1 ||
  fail "single tolerance run: $(cat "$dir/tol-single.out")"
for f in tolerance.json samples.csv; do
  cmp -s "$dir/tol-single/$f" "$dir/tol-merged/$f" || fail "the merged tolerance study's $f differs from one process's"
done

# A task that fails is named with its log; a command that cannot be sharded, or no sbatch, is refused.
"$hovs" -q slurm submit --shards 2 --wait --poll 0.5 --timeout 300 -- dataset --scene "$dir/missing.yaml" \
  --out "$dir/bad" > "$dir/bad.out" 2>&1
rc=$?
[ $rc -eq 2 ] || fail "a failing task: exit $rc, expected 2: $(cat "$dir/bad.out")"
grep -q "shard 0 failed" "$dir/bad.out" && grep -q "task-0.out" "$dir/bad.out" || fail "no shard named: $(cat "$dir/bad.out")"
[ ! -e "$dir/bad" ] || fail "a failed job left its output folder"
"$hovs" -q slurm submit -- calibrate --dataset x --out "$dir/x" > "$dir/x.out" 2>&1
[ $? -eq 2 ] && grep -q "cannot be sharded" "$dir/x.out" || fail "calibrate accepted: $(cat "$dir/x.out")"
PATH=/nonexistent "$hovs" -q slurm submit -- "${dataset[@]}" --out "$dir/nopath" > "$dir/nopath.out" 2>&1
[ $? -eq 2 ] && grep -q "sbatch: not found" "$dir/nopath.out" || fail "no sbatch: $(cat "$dir/nopath.out")"
echo "PASSED: 8 dataset shards and 4 tolerance shards through Slurm merged to the single-process outputs; failures named"
