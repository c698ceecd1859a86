#!/usr/bin/env bash
# A real single-node Slurm cluster (slurmctld + slurmd, munge authentication) from Debian's
# packages, without systemd: every file under one state directory, every daemon's pid recorded
# there and only those stopped. For tests and trials of the Make DAG through Slurm
# (`make ... LAUNCH="srun ..."`); a real cluster needs none of this.
#
#   scripts/slurm-cluster.sh start DIR   configure and start munged, slurmctld, slurmd in DIR;
#                                        prints `export SLURM_CONF=DIR/slurm.conf` (what the
#                                        client commands srun, sbatch, scancel need)
#   scripts/slurm-cluster.sh stop DIR    cancel every job, stop the daemons DIR's pids name
#
# The node offers $(nproc) CPUs and one fake GPU (gres.conf `File=/dev/null`), so jobs asking for
# `--gres=gpu:1` are scheduled as on a GPU node. Ports are chosen free at start.
set -euo pipefail

usage() { echo "usage: $0 start|stop DIR" >&2; exit 2; }
[ $# -eq 2 ] || usage
cmd="$1"
dir="$(mkdir -p "$2" && cd "$2" && pwd)"
node="$(hostname -s)"

stop_pids() { # stop the processes whose pids are in files "$@" (those still running), together
    local pids=() f pid
    for f in "$@"; do
        [ -f "$f" ] || continue
        pid="$(cat "$f")"
        if [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null; then
            kill "$pid" 2>/dev/null || true
            pids+=("$pid")
        fi
        rm -f "$f"
    done
    for _ in $(seq 100); do
        local alive=0
        for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
        [ "$alive" -eq 0 ] && return 0
        sleep 0.05
    done
    for pid in "${pids[@]}"; do kill -9 "$pid" 2>/dev/null || true; done
}

case "$cmd" in
start)
    for p in munged slurmctld slurmd srun sbatch scontrol; do
        command -v "$p" >/dev/null 2>&1 || { echo "error: $p not found (scripts/setup.sh --slurm installs Slurm and munge)" >&2; exit 1; }
    done
    if [ -f "$dir/slurmctld.pid" ] && kill -0 "$(cat "$dir/slurmctld.pid")" 2>/dev/null; then
        echo "error: $dir: a cluster is already running there (stop it first)" >&2
        exit 1
    fi
    mkdir -p "$dir/munge" "$dir/state" "$dir/spool" "$dir/log"
    chmod 700 "$dir/munge"
    # munge: its own key and socket, so that it neither needs nor disturbs a system munged.
    if [ ! -f "$dir/munge/munge.key" ]; then
        dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
        chmod 400 "$dir/munge/munge.key"
    fi
    munged --force --socket="$dir/munge/munge.socket" --key-file="$dir/munge/munge.key" \
        --pid-file="$dir/munge/munged.pid" --log-file="$dir/log/munged.log" \
        --seed-file="$dir/munge/munged.seed"
    cp "$dir/munge/munged.pid" "$dir/munged.pid"
    # Two free TCP ports for the daemons.
    read -r ctld_port d_port < <(python3 -c '
import socket
ss = [socket.socket() for _ in range(2)]
for s in ss: s.bind(("127.0.0.1", 0))
print(*[s.getsockname()[1] for s in ss])')
    cpus="$(nproc)"
    cat > "$dir/slurm.conf" <<CONF
ClusterName=luxest-test
SlurmctldHost=$node
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$d_port
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/affinity
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
GresTypes=gpu
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
JobRequeue=1
KillWait=5
InactiveLimit=0
MinJobAge=300
NodeName=$node CPUs=$cpus Gres=gpu:1 State=UNKNOWN
PartitionName=main Nodes=$node Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
CONF
    echo "Name=gpu File=/dev/null" > "$dir/gres.conf"
    export SLURM_CONF="$dir/slurm.conf"
    slurmctld -i -f "$dir/slurm.conf"
    slurmd -N "$node" -f "$dir/slurm.conf"
    # Ready when the node accepts jobs.
    for _ in $(seq 100); do
        if sinfo -h -N -o '%t' 2>/dev/null | grep -qE '^(idle|mix|alloc)'; then
            echo "export SLURM_CONF=$dir/slurm.conf"
            exit 0
        fi
        sleep 0.2
    done
    echo "error: the Slurm node did not come up within 20 s (logs in $dir/log)" >&2
    exit 1
    ;;
stop)
    if [ -f "$dir/slurm.conf" ] && [ -f "$dir/slurmctld.pid" ]; then
        # Jobs first: their steps would outlive the daemons. Wait (at most 10 s) until none is left.
        SLURM_CONF="$dir/slurm.conf" scancel --full --quiet --user="$(id -un)" 2>/dev/null || true
        for _ in $(seq 100); do
            [ -z "$(SLURM_CONF="$dir/slurm.conf" squeue -h -o %i 2>/dev/null)" ] && break
            sleep 0.1
        done
    fi
    stop_pids "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munged.pid"
    ;;
*) usage ;;
esac
