#!/usr/bin/env bash
# engines.sh: examples/sweep.lua's 3x2 grid run by a real job engine. The
# sweep runs once in one go (`femlod sweep ... --out WORK/direct`), then its
# `--emit-jobs` commands run under ENGINE into WORK/jobs, then `--collect`
# writes that folder's manifest; tests/sweep/compare.lua checks that both
# give the same digest and the same files (but for timings and the folder).
#
#   engines.sh parallel FEMLOD SOURCE_DIR WORK_DIR   GNU parallel, 2 at once
#   engines.sh slurm    FEMLOD SOURCE_DIR WORK_DIR   a one-node Slurm started
#                       here (munged, slurmctld, slurmd in a folder of their
#                       own under /tmp), the commands as a job array
#
# The slurm engine needs root and the Debian packages slurm-wlm and munge
# (README's second command installs them): without them it exits 77, which
# ctest counts as skipped. The parallel engine fails without `parallel`.
# Slurm's daemons are stopped on every way out (trap); a run killed with
# SIGKILL (ctest's timeout) leaves them running, so each run first stops
# the daemons a previous one recorded in WORK_DIR/slurm-runtime.
set -euo pipefail
engine=$1
femlod=$2
src=$(cd "$3" && pwd)
work=$4
grid=(--grid target=1500,3000,6000 --grid min_stretch=0.3,0.5)
npoints=6
say() { printf '%s: %s\n' "$engine" "$*"; }
fail() { printf '%s: FAILED: %s\n' "$engine" "$*" >&2; exit 1; }
skip() { printf '%s: SKIPPED: %s\n' "$engine" "$*"; exit 77; }

case $engine in
parallel)
    command -v parallel >/dev/null || fail "GNU parallel not found (README's second command installs it)"
    ;;
slurm)
    [ "$(id -u)" = 0 ] || skip "not root (a one-node Slurm needs root)"
    for b in munged munge unmunge slurmctld slurmd sbatch squeue sinfo scontrol scancel; do
        command -v "$b" >/dev/null || skip "$b not found (Debian packages slurm-wlm and munge)"
    done
    ;;
*) fail "unknown engine '$engine' (parallel or slurm)" ;;
esac

# {====== Slurm: start, stop
rt= # the daemons' folder
job=
# Whether pid $1 is a live process named $2 (a pid can be reused; a zombie
# has stopped).
alive() {
    [ "$(cat "/proc/$1/comm" 2>/dev/null)" = "$2" ] && ! grep -q '^[0-9]* ([^)]*) Z' "/proc/$1/stat" 2>/dev/null
}
# Cancels every job of the Slurm whose folder is $1 (if it still answers)
# and waits (10 s at most) until its queue is empty, so that no task goes on
# writing once the daemons are gone.
cancel_jobs() {
    [ -f "$1/slurm.conf" ] || return 0
    SLURM_CONF="$1/slurm.conf" scancel --user="$(id -un)" 2>/dev/null || return 0
    local n
    for n in $(seq 20); do
        [ -z "$(SLURM_CONF="$1/slurm.conf" squeue -h 2>/dev/null)" ] && break
        sleep 0.5
    done
}
# Stops the daemons whose pid files are in folder $1.
stop_daemons() {
    local dir=$1 f pid name n
    for f in slurmd:slurmd.pid slurmctld:slurmctld.pid munged:munge/munged.pid; do
        name=${f%%:*}
        [ -s "$dir/${f#*:}" ] || continue
        pid=$(cat "$dir/${f#*:}")
        alive "$pid" "$name" || continue
        kill "$pid" 2>/dev/null || continue
        for n in $(seq 50); do
            alive "$pid" "$name" || break
            sleep 0.2
        done
        alive "$pid" "$name" && kill -KILL "$pid" 2>/dev/null
        say "stopped $name (pid $pid)"
    done
}
cleanup() {
    local status=$?
    trap - EXIT INT TERM
    trap '' PIPE # a closed output must not stop the clean-up half-way
    set +e
    [ -n "$rt" ] || exit "$status"
    if [ "$status" != 0 ]; then
        for log in "$rt"/slurmctld.log "$rt"/slurmd.log "$rt"/munge/munged.log; do
            [ -f "$log" ] && { echo "---- last lines of $(basename "$log")"; tail -n 15 "$log"; }
        done
        for out in "$work"/slurm/task-*.out; do
            [ -f "$out" ] && { echo "---- $(basename "$out")"; tail -n 5 "$out"; }
        done
    fi
    [ "$status" != 0 ] && cancel_jobs "$rt"
    stop_daemons "$rt"
    mkdir -p "$work/slurm"
    cp "$rt"/*.log "$rt"/munge/munged.log "$work/slurm/" 2>/dev/null || true
    rm -rf "$rt"
    rm -f "$work/slurm-runtime"
    exit "$status"
}

# The Slurm of a previous run killed before its trap ran.
stop_stale() {
    [ -s "$work/slurm-runtime" ] || return 0
    local old
    old=$(cat "$work/slurm-runtime")
    case $old in
    /tmp/femlod-slurm.*)
        say "stopping the Slurm a killed run left in $old"
        cancel_jobs "$old"
        stop_daemons "$old"
        rm -rf "$old"
        ;;
    esac
    rm -f "$work/slurm-runtime"
}

start_slurm() {
    local port
    for port in 6817 6818; do
        if (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
            fail "port $port is in use (another Slurm?): Slurm's daemons listen on 6817 and 6818"
        fi
    done
    # Under /tmp: a socket's path has at most 107 bytes, and munged wants
    # every folder above its socket searchable by all.
    rt=$(mktemp -d /tmp/femlod-slurm.XXXXXX)
    echo "$rt" > "$work/slurm-runtime"
    trap cleanup EXIT
    trap 'exit 130' INT
    trap 'exit 143' TERM
    chmod 755 "$rt"
    mkdir -m 755 "$rt/munge"
    mkdir "$rt/state" "$rt/spool"
    # munged with a key, socket, pid and log of its own: a system munged, if
    # any, is left alone.
    dd if=/dev/urandom of="$rt/munge/munge.key" bs=1024 count=1 status=none
    chmod 400 "$rt/munge/munge.key"
    munged --force --socket="$rt/munge/munge.sock" --key-file="$rt/munge/munge.key" \
        --log-file="$rt/munge/munged.log" --pid-file="$rt/munge/munged.pid" \
        --seed-file="$rt/munge/munged.seed" || fail "munged did not start"
    munge -S "$rt/munge/munge.sock" -n | unmunge -S "$rt/munge/munge.sock" >/dev/null ||
        fail "munge cannot encode and decode a credential"
    local host node
    host=$(hostname -s)
    # The node as slurmd sees it (CPUs, sockets, cores, memory), on the
    # loopback address; names resolve to 127.0.0.1 so no DNS is needed.
    node=$(slurmd -C | head -n 1)
    case $node in "NodeName=$host "*) ;; *) fail "slurmd -C gave '$node'" ;; esac
    cat > "$rt/slurm.conf" <<EOF
ClusterName=femlodtest
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$rt/munge/munge.sock
CommunicationParameters=NoInAddrAny
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
StateSaveLocation=$rt/state
SlurmdSpoolDir=$rt/spool
SlurmctldPidFile=$rt/slurmctld.pid
SlurmdPidFile=$rt/slurmd.pid
SlurmctldLogFile=$rt/slurmctld.log
SlurmdLogFile=$rt/slurmd.log
ReturnToService=2
MpiDefault=none
MailProg=/bin/true
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
    export SLURM_CONF=$rt/slurm.conf
    slurmctld -f "$SLURM_CONF" || fail "slurmctld did not start"
    slurmd -f "$SLURM_CONF" || fail "slurmd did not start"
    local state= i
    for i in $(seq 120); do
        state=$(sinfo -h -n "$host" -o %t 2>/dev/null || true)
        [ "$state" = idle ] && break
        sleep 0.5
    done
    [ "$state" = idle ] || fail "node $host not idle after 60 s (sinfo: '$state')"
    say "Slurm $(sinfo -V | cut -d' ' -f2) up: node $host idle ($rt)"
}
# }======

mkdir -p "$work"
[ "$engine" = slurm ] && stop_stale
rm -rf "$work/direct" "$work/jobs" "$work/jobs.txt" "$work/slurm" "$work/parallel.log"
cd "$src"

# The sweep in one go.
"$femlod" -q sweep examples/sweep.lua "${grid[@]}" --out "$work/direct" --jobs 2 ||
    fail "the sweep in one go failed"
# One command per point.
"$femlod" sweep examples/sweep.lua "${grid[@]}" --out "$work/jobs" --emit-jobs > "$work/jobs.txt"
[ "$(wc -l < "$work/jobs.txt")" -eq "$npoints" ] || fail "--emit-jobs gave $(wc -l < "$work/jobs.txt") lines"

case $engine in
parallel)
    # The exit status is the number of jobs that failed; the job log has a
    # line per command with its exit value (column 7).
    parallel --will-cite -j 2 --joblog "$work/parallel.log" < "$work/jobs.txt" > "$work/parallel.out" ||
        fail "parallel: $? job(s) failed (log: $work/parallel.log)"
    ran=$(awk 'NR > 1 && $7 == 0' "$work/parallel.log" | wc -l)
    [ "$ran" -eq "$npoints" ] || fail "parallel's job log has $ran commands that exited 0"
    say "GNU parallel $(parallel --will-cite --version | head -n 1 | cut -d' ' -f3) ran $ran commands, each exit 0"
    ;;
slurm)
    start_slurm
    mkdir -p "$work/slurm"
    # The script of docs/cli.md: line SLURM_ARRAY_TASK_ID of jobs.txt.
    cat > "$work/slurm/sweep.sbatch" <<EOF
#!/bin/sh
#SBATCH --job-name=femlod-sweep
#SBATCH --array=1-$npoints
#SBATCH --cpus-per-task=1
#SBATCH --time=00:10:00
echo "task \$SLURM_ARRAY_TASK_ID of array job \$SLURM_ARRAY_JOB_ID on \$SLURMD_NODENAME"
sh -c "\$(sed -n "\${SLURM_ARRAY_TASK_ID}p" "$work/jobs.txt")"
EOF
    job=$(sbatch --parsable --chdir="$work" --output="$work/slurm/task-%a.out" "$work/slurm/sweep.sbatch")
    job=${job%%;*}
    say "submitted array job $job ($npoints tasks)"
    left=
    for i in $(seq 240); do
        left=$(squeue -h -j "$job" -o %i 2>/dev/null | wc -l)
        [ "$left" -eq 0 ] && break
        sleep 0.5
    done
    [ "$left" -eq 0 ] || fail "the array job is still queued or running after 120 s"
    # Slurm keeps finished jobs for MinJobAge (300 s): every task of the
    # array, completed with exit code 0.
    scontrol -o show job "$job" > "$work/slurm/jobs.txt"
    done_ok=$(grep -c "ArrayJobId=$job .*JobState=COMPLETED .*ExitCode=0:0" "$work/slurm/jobs.txt" || true)
    [ "$done_ok" -eq "$npoints" ] || { cat "$work/slurm/jobs.txt"; fail "$done_ok of $npoints tasks COMPLETED with exit code 0"; }
    for t in $(seq "$npoints"); do
        grep -q "^task $t of array job $job on " "$work/slurm/task-$t.out" ||
            fail "task-$t.out does not say it ran as task $t of job $job"
    done
    say "array job $job: $done_ok tasks COMPLETED, ExitCode=0:0"
    ;;
esac

# The manifest from the points the engine ran.
"$femlod" sweep examples/sweep.lua "${grid[@]}" --out "$work/jobs" --collect > "$work/collect.out" ||
    { cat "$work/collect.out"; fail "--collect failed"; }
tail -n 2 "$work/collect.out" | head -n 1
"$femlod" run "$src/tests/sweep/compare.lua" direct="$work/direct" jobs="$work/jobs" points=$npoints engine="$engine"
