#!/usr/bin/env bash
# slurm-local.sh: start and stop a throwaway single-node Slurm cluster for tests (the
# tests of `skg-solve sweep --slurm` in crates/skg-cli/tests/slurm.rs start one with it;
# docs/sweeps.md, "Running a sweep on a cluster").
#
#   slurm-local.sh start DIR    install Debian's Slurm 22.05 + MUNGE if missing, start
#                               munged, slurmctld and slurmd with everything under DIR,
#                               wait until the node is idle; prints `export ...` lines
#                               (also written to DIR/env.sh)
#   slurm-local.sh stop DIR     cancel jobs, stop the daemons by their recorded PIDs
#                               (TERM, then KILL), remove leftover job steps; idempotent
#   slurm-local.sh status DIR   exit 0 if all three daemons of DIR are running, else 3
#   slurm-local.sh env DIR      print the `export ...` lines again
#
# No systemd is needed or used; must run as root (SlurmUser=root). Nothing is written
# to /etc by this script (the Debian packages themselves create /etc/munge, /etc/slurm).
#
# Environment (all optional):
#   SLURM_LOCAL_START_TIMEOUT  seconds to wait for an idle node (default 60)
#   SLURM_LOCAL_STOP_TIMEOUT   seconds between TERM and KILL (default 15)
#   SLURM_LOCAL_PORT           slurmctld port; slurmd uses PORT+1 (default: a free pair
#                              derived from DIR, so several clusters can coexist)
#   SLURM_LOCAL_CPUS           CPUs of the node (default: nproc)
#   SLURM_LOCAL_MEM_MB         RealMemory of the node (default: 95% of MemTotal)
#   SLURM_LOCAL_MIN_JOB_AGE    seconds a finished job stays visible to scontrol/squeue
#                              (default 600; there is no accounting, so no sacct)
set -euo pipefail

readonly PACKAGES=(slurmctld slurmd slurm-client munge)
readonly DAEMONS=(munged slurmctld slurmd)
START_TIMEOUT=${SLURM_LOCAL_START_TIMEOUT:-60}
STOP_TIMEOUT=${SLURM_LOCAL_STOP_TIMEOUT:-15}
MIN_JOB_AGE=${SLURM_LOCAL_MIN_JOB_AGE:-600}
PROG=${0##*/}

log() { printf '%s: %s\n' "$PROG" "$*" >&2; }
die() {
    printf '%s: error: %s\n' "$PROG" "$*" >&2
    exit 1
}
usage() {
    printf 'usage: %s start|stop|status|env DIR\n' "$PROG" >&2
    exit 2
}

# ---------------------------------------------------------------- packages

installed() { [[ $(dpkg-query -W -f='${Status}' "$1" 2>/dev/null) == "install ok installed" ]]; }

install_packages() {
    local missing=() p
    for p in "${PACKAGES[@]}"; do
        installed "$p" || missing+=("$p")
    done
    ((${#missing[@]} == 0)) && return 0
    log "installing ${missing[*]} (apt-get, no recommends)"
    local t0=$SECONDS
    local aptlog
    aptlog=$(mktemp)
    # No systemd here, and the packages' maintainer scripts must not start a system
    # munged/slurmd of their own: a policy-rc.d that says "no" (if none exists yet).
    local policy=/usr/sbin/policy-rc.d made_policy=
    if [[ ! -e $policy ]]; then
        printf '#!/bin/sh\nexit 101\n' >"$policy"
        chmod 755 "$policy"
        made_policy=1
    fi
    local rc=0
    {
        export DEBIAN_FRONTEND=noninteractive
        apt-get install -y -q --no-install-recommends "${missing[@]}" ||
            { apt-get update -q && apt-get install -y -q --no-install-recommends "${missing[@]}"; }
    } >"$aptlog" 2>&1 || rc=$?
    [[ -n $made_policy ]] && rm -f "$policy"
    if ((rc != 0)); then
        tail -n 20 "$aptlog" >&2
        rm -f "$aptlog"
        die "apt-get install ${missing[*]} failed (exit $rc)"
    fi
    rm -f "$aptlog"
    log "installed ${missing[*]} in $((SECONDS - t0)) s"
}

# ---------------------------------------------------------------- processes

# PID recorded for daemon $2 of cluster $1, if that process is still ours.
ours() {
    local dir=$1 name=$2 pid
    [[ -r $dir/pids/$name.pid ]] || return 1
    pid=$(<"$dir/pids/$name.pid")
    [[ $pid =~ ^[0-9]+$ ]] || return 1
    # Guard against PID reuse: same program, and its command line names DIR.
    [[ -r /proc/$pid/comm && $(<"/proc/$pid/comm") == "$name" ]] || return 1
    grep -qzF -- "$dir/" "/proc/$pid/cmdline" 2>/dev/null || return 1
    printf '%s\n' "$pid"
}

alive() { [[ -d /proc/$1 ]] && ! grep -q '^State:[[:space:]]*Z' "/proc/$1/status" 2>/dev/null; }

# terminate GRACE PID...: send TERM, wait up to GRACE seconds, then KILL; wait until
# all are gone.
terminate() {
    local grace=$1
    shift
    (($# == 0)) && return 0
    local pid deadline
    kill -TERM "$@" 2>/dev/null || true
    deadline=$((SECONDS + grace))
    for pid in "$@"; do
        while alive "$pid" && ((SECONDS < deadline)); do sleep 0.1; done
    done
    for pid in "$@"; do
        if alive "$pid"; then
            log "PID $pid ($(cat "/proc/$pid/comm" 2>/dev/null)) ignored TERM for ${grace}s: KILL"
            kill -KILL "$pid" 2>/dev/null || true
        fi
    done
    for pid in "$@"; do
        deadline=$((SECONDS + 5))
        while alive "$pid" && ((SECONDS < deadline)); do sleep 0.1; done
    done
}

# Processes that carry the marker SLURM_LOCAL_DIR=DIR in their environment: the three
# daemons (set by `launch`) and the slurmstepd processes that slurmd forks for jobs.
# marked DIR munged|other: print those whose command is munged, or all others together
# with all their descendants (the jobs' processes).
marked() {
    local dir=$1 which=$2 p comm roots=()
    local found=()
    mapfile -t found < <(grep -lzxF "SLURM_LOCAL_DIR=$dir" /proc/[0-9]*/environ 2>/dev/null |
        sed -n 's|^/proc/\([0-9]*\)/environ$|\1|p')
    for p in "${found[@]}"; do
        alive "$p" || continue
        comm=$(cat "/proc/$p/comm" 2>/dev/null) || continue
        if [[ $which == munged ]]; then
            [[ $comm == munged ]] && printf '%s\n' "$p"
        elif [[ $comm != munged ]]; then
            roots+=("$p")
        fi
    done
    ((${#roots[@]} == 0)) && return 0
    # Walk the process tree (pid -> ppid from /proc/*/stat) down from these roots.
    local -A parent=() keep=()
    local stat rest state ppid
    for p in /proc/[0-9]*/stat; do
        read -r stat 2>/dev/null <"$p" || continue
        rest=${stat##*) } # the fields after "(comm) "
        read -r state ppid _ <<<"$rest"
        parent[${stat%% *}]=$ppid
    done
    for p in "${roots[@]}"; do keep[$p]=1; done
    local changed=1
    while ((changed)); do
        changed=0
        for p in "${!parent[@]}"; do
            if [[ -z ${keep[$p]:-} && -n ${keep[${parent[$p]}]:-} ]]; then
                keep[$p]=1
                changed=1
            fi
        done
    done
    : "$state"
    for p in "${!keep[@]}"; do alive "$p" && printf '%s\n' "$p"; done
    return 0
}

# ---------------------------------------------------------------- helpers

# A free port pair (P, P+1) for slurmctld and slurmd: listening TCP ports are
# read from /proc/net/tcp*, the search starts at a base derived from DIR.
pick_port() {
    local dir=$1
    if [[ -n ${SLURM_LOCAL_PORT:-} ]]; then
        printf '%s\n' "$SLURM_LOCAL_PORT"
        return
    fi
    local -A used=()
    local f local_addr state hex
    for f in /proc/net/tcp /proc/net/tcp6; do
        [[ -r $f ]] || continue
        while read -r _ local_addr _ state _; do
            [[ $state == 0A ]] || continue
            hex=${local_addr##*:}
            used[$((16#$hex))]=1
        done < <(tail -n +2 "$f")
    done
    local sum port i
    sum=$(printf '%s' "$dir" | cksum)
    sum=${sum%% *}
    port=$((20000 + (sum % 5000) * 2)) # 20000..29998, even
    for ((i = 0; i < 5000; i++)); do
        if [[ -z ${used[$port]:-} && -z ${used[$((port + 1))]:-} ]]; then
            printf '%s\n' "$port"
            return
        fi
        port=$((port + 2))
        ((port > 29998)) && port=20000
    done
    die "no free TCP port pair found in 20000-29999"
}

env_lines() {
    local dir=$1
    printf 'export SLURM_CONF=%q\n' "$dir/etc/slurm.conf"
}

tail_logs() {
    local dir=$1 d f
    for d in "${DAEMONS[@]}"; do
        # Each daemon's own log file if it got that far, else its captured stderr.
        f=$dir/log/$d.log
        [[ -s $f ]] || f=$dir/log/$d.out
        [[ -s $f ]] || continue
        printf -- '----- last lines of %s\n' "$f" >&2
        tail -n 12 "$f" >&2
    done
}

running_all() {
    local dir=$1 d
    for d in "${DAEMONS[@]}"; do ours "$dir" "$d" >/dev/null || return 1; done
}

node_state() {
    SLURM_CONF=$1/etc/slurm.conf timeout 10 sinfo -h -N -n "$2" -o '%T' 2>/dev/null | head -n 1
}

# ---------------------------------------------------------------- start

# Is the daemon just launched by this script still there? (Right after the fork its
# command name is not yet the daemon's, so `ours` would be too strict here.)
started() { alive "$(<"$1/pids/$2.pid")"; }

write_conf() {
    local dir=$1 node=$2 port=$3 cpus mem_mb
    cpus=${SLURM_LOCAL_CPUS:-$(nproc)}
    if [[ -n ${SLURM_LOCAL_MEM_MB:-} ]]; then
        mem_mb=$SLURM_LOCAL_MEM_MB
    else
        local kb
        kb=$(awk '/^MemTotal:/ {print $2}' /proc/meminfo)
        mem_mb=$((kb * 95 / 100 / 1024))
    fi
    cat >"$dir/etc/slurm.conf" <<EOF
# Written by slurm-local.sh: a single-node test cluster, everything under $dir.
ClusterName=skglocal
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
# Schedule batch jobs as soon as they are submitted or resources free up (the default
# batch_sched_delay=3 adds up to 3 s per wave of array tasks).
SchedulerParameters=batch_sched_delay=0
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
# Reject at submission what the node can never run (e.g. --cpus-per-task above its
# CPUs) instead of leaving it pending forever with Reason=PartitionConfig.
EnforcePartLimits=ALL
MailProg=/bin/true
ReturnToService=2
MinJobAge=$MIN_JOB_AGE
KillWait=5
InactiveLimit=0
SlurmdTimeout=300
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=debug Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
}

# Start "$@" detached (own session), stdout/stderr to DIR/log/NAME.out, record PID.
# The daemons get the environment marker SLURM_LOCAL_DIR=DIR, which the slurmstepd
# processes that slurmd forks for jobs inherit: `stop` finds leftovers by it.
# (env and setsid exec in place, so $! is the daemon's own PID; 9>&-: the daemons
# must not inherit the lock on DIR/.lock.)
launch() {
    local dir=$1 name=$2
    shift 2
    env "SLURM_CONF=$dir/etc/slurm.conf" "SLURM_LOCAL_DIR=$dir" \
        setsid "$@" </dev/null >"$dir/log/$name.out" 2>&1 9>&- &
    printf '%s\n' "$!" >"$dir/pids/$name.pid"
}

start() {
    local dir=$1
    [[ $(id -u) -eq 0 ]] || die "must run as root (SlurmUser=root, package installs)"
    install_packages

    if running_all "$dir"; then
        local now
        now=$(node_state "$dir" "$(<"$dir/node")")
        if [[ $now == idle || $now == mixed || $now == allocated ]]; then
            log "already running in $dir"
            env_lines "$dir" | tee "$dir/env.sh"
            return 0
        fi
        log "daemons of $dir run but the node is not usable: restarting"
    fi
    # Anything left from an earlier (killed or half-started) run goes first.
    stop "$dir" quiet

    # UNIX socket paths are limited to 107 bytes; slurmd also puts sockets in its spool.
    ((${#dir} <= 80)) || die "DIR path too long for UNIX sockets (${#dir} > 80 bytes): $dir"
    [[ $dir != *[[:space:]]* ]] || die "DIR must not contain white space (slurm.conf): $dir"

    rm -rf "${dir:?}"/{etc,state,spool,run,log,munge,pids}
    mkdir -p "$dir"/{etc,state,spool,run,log,pids}
    # munged insists: key and socket directory not writable by group/other, socket
    # directory searchable by all (0711); DIR itself must be searchable too.
    chmod go-w,a+x "$dir"
    install -d -m 0711 "$dir/munge"
    mungekey --create --keyfile="$dir/munge/munge.key" 2>"$dir/log/mungekey.out" ||
        die "mungekey failed: $(cat "$dir/log/mungekey.out")"

    local node port
    node=$(hostname -s)
    printf '%s\n' "$node" >"$dir/node"
    port=$(pick_port "$dir")
    write_conf "$dir" "$node" "$port"
    env_lines "$dir" >"$dir/env.sh"

    launch "$dir" munged munged --foreground \
        --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
        --pid-file="$dir/run/munged.pid" --seed-file="$dir/munge/munged.seed" \
        --log-file="$dir/log/munged.log"
    local deadline=$((SECONDS + 10))
    until munge -n -S "$dir/munge/munge.socket" 2>/dev/null |
        unmunge -S "$dir/munge/munge.socket" >/dev/null 2>&1; do
        if ! started "$dir" munged || ((SECONDS >= deadline)); then
            tail_logs "$dir"
            stop "$dir" quiet
            die "munged did not come up (see $dir/log)"
        fi
        sleep 0.1
    done

    launch "$dir" slurmctld slurmctld -D -f "$dir/etc/slurm.conf"
    launch "$dir" slurmd slurmd -D -f "$dir/etc/slurm.conf" -N "$node"

    local state='' d t0=$SECONDS
    deadline=$((SECONDS + START_TIMEOUT))
    while :; do
        for d in "${DAEMONS[@]}"; do
            if ! started "$dir" "$d"; then
                tail_logs "$dir"
                stop "$dir" quiet
                die "$d exited during start-up (logs above, all in $dir/log)"
            fi
        done
        state=$(node_state "$dir" "$node")
        [[ $state == idle ]] && break
        # inval/drain: slurmctld rejected the node (e.g. fewer CPUs or less memory
        # than configured); waiting will not help.
        if [[ $state == inval* || $state == drain* ]] || ((SECONDS >= deadline)); then
            tail_logs "$dir"
            SLURM_CONF=$dir/etc/slurm.conf sinfo -R >&2 2>/dev/null || true
            stop "$dir" quiet
            die "node $node not idle after $((SECONDS - t0)) s (state '${state:-none}'); logs above"
        fi
        sleep 0.2
    done
    log "cluster up in $dir: node $node idle, slurmctld port $port"
    env_lines "$dir"
}

# ---------------------------------------------------------------- stop

stop() {
    local dir=$1 quiet=${2:-}
    local ctld
    # Cancel what is still queued or running so that slurmd cleans up its steps.
    if ctld=$(ours "$dir" slurmctld) && [[ -n $ctld ]] && ours "$dir" slurmd >/dev/null; then
        local ids deadline
        export SLURM_CONF=$dir/etc/slurm.conf
        ids=$(timeout 10 squeue -h -o '%A' 2>/dev/null | sort -u | tr '\n' ' ') || ids=
        if [[ -n ${ids// /} ]]; then
            # shellcheck disable=SC2086 # word splitting of the id list is intended
            timeout 10 scancel $ids 2>/dev/null || true
            deadline=$((SECONDS + STOP_TIMEOUT))
            while [[ -n $(timeout 10 squeue -h -o '%A' 2>/dev/null) ]] && ((SECONDS < deadline)); do
                sleep 0.2
            done
        fi
        unset SLURM_CONF
    fi
    local pids=() d p
    for d in slurmd slurmctld; do
        p=$(ours "$dir" "$d") && pids+=("$p")
    done
    terminate "$STOP_TIMEOUT" "${pids[@]}"
    # Whatever else carries DIR's marker: job steps whose slurmd is gone (or that
    # outlived the grace time), daemons whose PID records were lost (DIR deleted).
    mapfile -t pids < <(marked "$dir" other)
    if ((${#pids[@]})); then
        log "killing ${#pids[@]} leftover process(es) of $dir: $(
            for p in "${pids[@]}"; do cat "/proc/$p/comm" 2>/dev/null; done | sort | uniq -c | xargs
        )"
        terminate 2 "${pids[@]}"
    fi
    # munged last: slurmd and slurmctld need it while they shut down.
    mapfile -t pids < <({
        ours "$dir" munged || true
        marked "$dir" munged
    } | sort -u)
    terminate "$STOP_TIMEOUT" "${pids[@]}"
    rm -f "$dir"/pids/*.pid "$dir"/run/*.pid
    [[ -z $quiet ]] && log "stopped $dir"
    return 0
}

status() {
    local dir=$1 d p rc=0
    for d in "${DAEMONS[@]}"; do
        if p=$(ours "$dir" "$d"); then
            printf '%-10s running (PID %s)\n' "$d" "$p"
        else
            printf '%-10s not running\n' "$d"
            rc=3
        fi
    done
    if ((rc == 0)); then
        printf 'node       %s\n' "$(node_state "$dir" "$(<"$dir/node")")"
    fi
    return "$rc"
}

# ---------------------------------------------------------------- main

(($# == 2)) || usage
cmd=$1
DIR=$(realpath -m -- "$2")
# One start/stop at a time per DIR.
if [[ $cmd == start || ($cmd == stop && -d $DIR) ]]; then
    [[ $DIR != / ]] || die "DIR must not be /"
    mkdir -p "$DIR"
    exec 9>>"$DIR/.lock"
    flock -w 300 9 || die "another $PROG holds $DIR/.lock"
fi
case $cmd in
start)
    # Never take over (and later wipe parts of) a directory that is not ours.
    if [[ ! -e $DIR/.slurm-local ]]; then
        shopt -s nullglob dotglob
        for f in "$DIR"/*; do
            [[ $f == "$DIR/.lock" ]] || die "$DIR is not empty and was not made by $PROG"
        done
        shopt -u nullglob dotglob
    fi
    touch "$DIR/.slurm-local"
    start "$DIR"
    ;;
stop) stop "$DIR" ;;
status) status "$DIR" ;;
env) env_lines "$DIR" ;;
*) usage ;;
esac
