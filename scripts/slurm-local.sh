#!/usr/bin/env bash
# A single-node Slurm cluster on this machine (docs/cluster.md): Debian's slurm-wlm and
# munge, their daemons started by hand (no systemd), every file of theirs in one folder.
# No cgroups (proctrack/linuxproc, task/none), so it runs in a container; the node is this
# machine, `hostname`, with all its CPUs; accounting is off (squeue and scontrol, not sacct).
#
# Usage:
#   scripts/slurm-local.sh install   # as root: apt-get install slurm-wlm munge where missing
#   scripts/slurm-local.sh start     # writes DIR/slurm.conf, starts munged, slurmctld, slurmd
#   scripts/slurm-local.sh stop      # cancels every job, stops the three daemons
# DIR is $SLURM_LOCAL_DIR (default /tmp/sshc-slurm). Clients find the cluster through
# SLURM_CONF=DIR/slurm.conf, which `start` prints; the daemons listen on ports
# $SLURM_LOCAL_PORT and the next (default 6817, 6818).
set -euo pipefail
dir=${SLURM_LOCAL_DIR:-/tmp/sshc-slurm}
port=${SLURM_LOCAL_PORT:-6817}
conf="$dir/slurm.conf"

missing() {
    local m=()
    for c in munged mungekey slurmctld slurmd sbatch; do
        command -v "$c" >/dev/null 2>&1 || m+=("$c")
    done
    echo "${m[@]:-}"
}

# Stops the process of pid file $1, waiting up to 10 s for it to end.
stop_pid() {
    [ -f "$1" ] || return 0
    local pid
    pid=$(cat "$1")
    if [ -n "$pid" ] && kill "$pid" 2>/dev/null; then
        for _ in $(seq 100); do
            kill -0 "$pid" 2>/dev/null || break
            sleep 0.1
        done
        kill -9 "$pid" 2>/dev/null || true
    fi
    rm -f "$1"
}

case "${1:-}" in
install)
    if [ -n "$(missing)" ]; then
        if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
            echo "installing: slurm-wlm munge"
            apt-get update -qq
            DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
        else
            echo "missing: $(missing); install them with: sudo apt-get install -y slurm-wlm munge"
            exit 1
        fi
    fi
    ;;
start)
    if [ -n "$(missing)" ]; then
        echo "missing: $(missing); run: scripts/slurm-local.sh install"
        exit 1
    fi
    mkdir -p "$dir/state" "$dir/spool" "$dir/log"
    chmod 700 "$dir"
    host=$(hostname)
    # munge: a key of its own, its socket in DIR (root runs it here: --force)
    [ -f "$dir/munge.key" ] || mungekey --create --keyfile="$dir/munge.key" >/dev/null
    chmod 400 "$dir/munge.key"
    munged --force --key-file="$dir/munge.key" --socket="$dir/munge.socket" \
        --pid-file="$dir/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munged.seed"
    cpus=$(nproc)
    mem=$(( $(free -m | awk '/Mem:/{print $2}') - 1024 ))
    cat >"$conf" <<CONF
ClusterName=sshc-local
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=$(id -un)
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge.socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
SchedulerParameters=sched_interval=1
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
    export SLURM_CONF="$conf"
    slurmctld -f "$conf"
    slurmd -f "$conf"
    # the node reads idle once slurmd has registered
    for _ in $(seq 150); do
        if sinfo -h -o %T 2>/dev/null | grep -qx idle; then
            echo "slurm: node $host idle ($cpus CPUs); export SLURM_CONF=$conf"
            exit 0
        fi
        sleep 0.2
    done
    echo "slurm: the node did not come up in 30 s:"
    sinfo 2>&1 || true
    tail -n 20 "$dir/log/slurmctld.log" "$dir/log/slurmd.log" 2>/dev/null || true
    exit 1
    ;;
stop)
    if [ -f "$conf" ] && command -v scancel >/dev/null 2>&1; then
        export SLURM_CONF="$conf"
        scancel --full --quiet --user="$(id -un)" 2>/dev/null || true
        for _ in $(seq 50); do
            [ -z "$(squeue -h 2>/dev/null)" ] && break
            sleep 0.2
        done
    fi
    stop_pid "$dir/slurmd.pid"
    stop_pid "$dir/slurmctld.pid"
    stop_pid "$dir/munged.pid"
    echo "slurm: stopped"
    ;;
*)
    echo "usage: scripts/slurm-local.sh install|start|stop"
    exit 2
    ;;
esac
