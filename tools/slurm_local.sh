#!/usr/bin/env bash
# A single-node SLURM on this machine, and the quick workflow through it:
#
#   tools/slurm_local.sh [REPO]             as root; REPO: default this script's repository
#   tools/slurm_local.sh --exec CMD [REPO]  start SLURM, run the shell command CMD in REPO
#                                           instead of step 3, stop SLURM (CMD's status)
#
# 1. installs SLURM and munge if missing (Debian: apt-get install slurmctld slurmd
#    slurm-client munge) and the executor plugin (the `cluster` extra of pyproject.toml);
# 2. starts munged (as user munge) and, with a one-node slurm.conf (no job accounting;
#    state and logs in $HPFEBE_SLURM_DIR, default /tmp/hpfebe-slurm), slurmctld and
#    slurmd, directly (no systemd);
# 3. in REPO: `snakemake --profile profiles/slurm --workflow-profile none
#    --configfile config/quick.yaml --forceall` (every job through sbatch, whatever
#    results/ holds: this rewrites REPO's results/ and report/ with the quick ones), checks
#    report/index.html, then checks that a second call plans nothing (dry run) and submits
#    nothing (real run, no new SLURM job);
# 4. stops every daemon it started (trap on EXIT, also after a failure) and prints the
#    timings.  Exits non-zero on any failure.  Run it again on the same machine: it
#    reuses what is installed and starts from a clean SLURM state each time.
#
# The config is /etc/slurm/slurm.conf (SLURM's default path: the executor plugin's job
# step drops SLURM_CONF from the environment of its srun, so no other path works); an
# existing one that this script did not write is an error, and the one it wrote is
# removed again at the end.
#
# Environment: HPFEBE_SLURM_DIR (state, logs; default /tmp/hpfebe-slurm),
# HPFEBE_SLURM_CONF_EXTRA (lines appended to slurm.conf),
# HPFEBE_SLURM_KEEP_LOGS=1 (keep SLURM's per-job logs in REPO/.snakemake/slurm_logs),
# HPFEBE_SLURM_ORPHAN_CHECK=1 (before step 3: start the workflow, kill -9 the main
# Snakemake while jobs run, check that no job writes or removes a result file after it:
# the job watch, and the parent check before every rename of a result,
# hpfebe.suite.watch.before_rename; ~1-2 min).
set -euo pipefail

SCRIPT_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
EXEC=""
if [[ "${1:-}" == --exec ]]; then   # --exec CMD: only start SLURM, run CMD in REPO, stop
    EXEC="${2:?--exec needs a command}"; shift 2
fi
REPO="$(cd "${1:-${SCRIPT_DIR}/..}" && pwd)"
WORK="${HPFEBE_SLURM_DIR:-/tmp/hpfebe-slurm}"
CONF=/etc/slurm/slurm.conf
MARK="# Written by tools/slurm_local.sh"
WROTE_CONF=0
SNAKEMAKE_ARGS=(--profile profiles/slurm --workflow-profile none --configfile config/quick.yaml)
if [[ "${HPFEBE_SLURM_KEEP_LOGS:-0}" == 1 ]]; then
    SNAKEMAKE_ARGS+=(--slurm-keep-successful-logs)
fi

T0=${SECONDS}
TIMINGS=()
STEP=""
STEP_T0=${SECONDS}
step() {
    if [[ -n "${STEP}" ]]; then
        TIMINGS+=("$(printf '%5d s  %s' $((SECONDS - STEP_T0)) "${STEP}")")
    fi
    STEP="$*"; STEP_T0=${SECONDS}
    printf '\n=== slurm_local: %s (%s) ===\n' "$*" "$(date -u +%H:%M:%S)"
}
FAILURE=""               # what die() said: repeated after the logs, at the end
die() { FAILURE="$*"; echo "slurm_local: FAILED: $*" >&2; exit 1; }

# ------------------------------------------------------------------ teardown (on EXIT)
STARTED_PIDS=()          # daemons this run started, in start order (stopped in reverse)
STARTED_NAMES=()
ORPHAN_MAIN=""           # the Snakemake of the orphan check, while it runs
stop_pid() {             # stop_pid PID NAME: TERM, then KILL after 10 s
    local pid=$1 name=$2 i
    kill -0 "${pid}" 2>/dev/null || return 0
    kill -TERM "${pid}" 2>/dev/null || true
    for ((i = 0; i < 100; i++)); do
        kill -0 "${pid}" 2>/dev/null || { echo "stopped ${name} (pid ${pid})"; return 0; }
        sleep 0.1
    done
    echo "slurm_local: ${name} (pid ${pid}) ignored SIGTERM for 10 s: SIGKILL" >&2
    kill -KILL "${pid}" 2>/dev/null || true
}
on_exit() {
    local rc=$? i
    trap - EXIT
    set +e
    if ((rc != 0)); then
        FAILED_STEP=${STEP}
        echo "slurm_local: FAILED (exit ${rc}) in step '${STEP}'" >&2
        for f in "${WORK}"/log/slurmctld.log "${WORK}"/log/slurmd.log; do
            [[ -s "${f}" ]] && { echo "--- ${f} (last 20 lines)" >&2; tail -n 20 "${f}" >&2; }
        done
        find "${REPO}/results/logs" -name '*.log' -newer "${WORK}/started" 2>/dev/null \
            | sort | while read -r f; do
            echo "--- ${f} (last 10 lines)" >&2; tail -n 10 "${f}" >&2
        done
        if [[ -d "${REPO}/.snakemake/slurm_logs" ]]; then
            find "${REPO}/.snakemake/slurm_logs" -name '*.log' -newer "${WORK}/started" \
                2>/dev/null | head -n 5 | while read -r f; do
                echo "--- ${f} (last 20 lines)" >&2; tail -n 20 "${f}" >&2
            done
        fi
    fi
    if [[ -n "${STEP}" ]]; then step "stop the daemons"; fi
    if [[ -n "${ORPHAN_MAIN}" ]]; then kill -9 "${ORPHAN_MAIN}" 2>/dev/null; fi
    if ((${#STARTED_PIDS[@]})) && scontrol ping >/dev/null 2>&1; then
        squeue -h -o %i 2>/dev/null | xargs -r scancel 2>/dev/null   # jobs left by a failure
    fi
    for ((i = ${#STARTED_PIDS[@]} - 1; i >= 0; i--)); do
        stop_pid "${STARTED_PIDS[i]}" "${STARTED_NAMES[i]}"
    done
    if ((WROTE_CONF)); then rm -f "${CONF}"; fi
    STEP_T0=${STEP_T0:-${SECONDS}}
    TIMINGS+=("$(printf '%5d s  %s' $((SECONDS - STEP_T0)) "${STEP}")")
    printf '\n=== slurm_local timings ===\n'
    printf '%s\n' "${TIMINGS[@]}"
    printf '%5d s  total\n' $((SECONDS - T0))
    if ((rc == 0)); then
        echo "slurm_local: passed"
    else
        echo "slurm_local: FAILED (exit ${rc}) in step '${FAILED_STEP}'${FAILURE:+: ${FAILURE}}" >&2
    fi
    exit "${rc}"
}
trap on_exit EXIT
trap 'exit 130' INT
trap 'exit 143' TERM HUP

[[ "$(id -u)" == 0 ]] || die "run as root (apt-get, munged as user munge, slurmd)"
[[ -f "${REPO}/Snakefile" && -d "${REPO}/profiles/slurm" ]] \
    || die "${REPO} is not the hpfebe repository"

# One run at a time on a machine (one /etc/slurm/slurm.conf, SLURM's ports, the pid files
# in WORK): a second run waits for the first to end (30 min at most).
LOCK=/tmp/hpfebe-slurm_local.lock
exec 9>"${LOCK}"
if ! flock -n 9; then
    echo "slurm_local: another run of this script holds ${LOCK}: waiting for it"
    flock -w 1800 9 || die "another run of this script still holds ${LOCK} after 30 min"
fi

# ------------------------------------------------------------------ 1. install
step "install SLURM and munge"
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null \
        || ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends \
        slurmctld slurmd slurm-client munge >/dev/null
fi
dpkg-query -W -f '${Package} ${Version}\n' slurmctld slurmd slurm-client munge

step "install the executor plugin"
# `pip install -e REPO[cluster]` when the installed hpfebe is REPO's (or none is); when it
# is another checkout's (this script run in a scratch clone), only the extra's
# requirements, so as not to repoint that editable install.
INSTALLED="$(python -c 'import json, importlib.metadata as md
try:
    d = md.distribution("hpfebe")
except md.PackageNotFoundError:
    pass
else:
    print(json.loads(d.read_text("direct_url.json") or "{}").get("url", ""))')"
if [[ -z "${INSTALLED}" || "${INSTALLED}" == "file://${REPO}" ]]; then
    pip install -q -e "${REPO}[cluster]"
else
    echo "hpfebe is installed from ${INSTALLED}, not ${REPO}: installing only the cluster extra"
    mapfile -t CLUSTER_REQS < <(python -c 'import sys, tomllib
with open(sys.argv[1], "rb") as f:
    print("\n".join(tomllib.load(f)["project"]["optional-dependencies"]["cluster"]))' \
        "${REPO}/pyproject.toml")
    pip install -q "${CLUSTER_REQS[@]}"
fi
pip show snakemake-executor-plugin-slurm 2>/dev/null | grep -E '^(Name|Version)'

# ------------------------------------------------------------------ 2. daemons
step "start munged"
# Daemons left by an earlier run of this script that was killed outright (no trap ran;
# that run no longer holds the lock): only those whose pid file is in WORK, and only if
# the pid still runs that program.
for d in slurmd slurmctld; do
    if [[ -f "${WORK}/${d}.pid" ]]; then
        pid="$(cat "${WORK}/${d}.pid")"
        if [[ "$(cat "/proc/${pid}/comm" 2>/dev/null)" == "${d}" ]]; then
            echo "stopping ${d} (pid ${pid}) left by an earlier run"
            stop_pid "${pid}" "${d}"
        fi
        rm -f "${WORK}/${d}.pid"
    fi
done
if munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    echo "munged is running already: using it (and leaving it running)"
else
    install -d -o munge -g munge -m 0755 /run/munge
    install -d -o munge -g munge -m 0700 /var/log/munge /etc/munge
    install -d -o munge -g munge -m 0711 /var/lib/munge
    if [[ ! -s /etc/munge/munge.key ]]; then
        mungekey --create --keyfile /etc/munge/munge.key
    fi
    chown munge:munge /etc/munge/munge.key
    chmod 0400 /etc/munge/munge.key
    rm -f /run/munge/munged.pid
    runuser -u munge -- /usr/sbin/munged 9>&-   # forks into the background
    for ((i = 0; i < 50; i++)); do
        [[ -s /run/munge/munged.pid ]] && break
        sleep 0.1
    done
    [[ -s /run/munge/munged.pid ]] || die "munged did not start (see /var/log/munge/munged.log)"
    STARTED_PIDS+=("$(cat /run/munge/munged.pid)"); STARTED_NAMES+=(munged)
    munge -n | unmunge >/dev/null || die "munge credentials do not decode"
fi

step "start slurmctld and slurmd"
NODE="$(hostname -s)"
# The node as slurmd sees it; CPUs alone (with config_overrides): every logical CPU is
# one allocatable core under CR_Core_Memory, also on a machine with hyperthreads.
NODE_HW="$(slurmd -C | head -n 1)"
CPUS="$(sed -n 's/.*CPUs=\([0-9]*\).*/\1/p' <<<"${NODE_HW}")"
MEM="$(sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p' <<<"${NODE_HW}")"
[[ -n "${CPUS}" && -n "${MEM}" ]] \
    || die "cannot read CPUs/RealMemory from 'slurmd -C': ${NODE_HW}"
if [[ -e "${CONF}" ]] && ! grep -qF "${MARK}" "${CONF}"; then
    die "${CONF} exists and was not written by this script: a SLURM is configured here"
fi
rm -rf "${WORK}/state" "${WORK}/spool"          # a clean queue every run
mkdir -p "${WORK}/state" "${WORK}/spool" "${WORK}/log" /etc/slurm
touch "${WORK}/started"
WROTE_CONF=1
cat >"${CONF}" <<EOF
${MARK}: a one-node SLURM without job accounting.
ClusterName=hpfebe
SlurmctldHost=${NODE}(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=${WORK}/state
SlurmdSpoolDir=${WORK}/spool
SlurmctldPidFile=${WORK}/slurmctld.pid
SlurmdPidFile=${WORK}/slurmd.pid
SlurmctldLogFile=${WORK}/log/slurmctld.log
SlurmdLogFile=${WORK}/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/backfill
# start the next job as soon as one ends (defaults: up to ~3 s between them)
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
ReturnToService=2
SlurmdParameters=config_overrides
# finished jobs stay visible to squeue for 5 min: the plugin's squeue status command
# needs MinJobAge >= 3x its first status interval
MinJobAge=300
NodeName=${NODE} NodeAddr=127.0.0.1 CPUs=${CPUS} RealMemory=${MEM} State=UNKNOWN
PartitionName=debug Nodes=${NODE} Default=YES MaxTime=INFINITE State=UP
${HPFEBE_SLURM_CONF_EXTRA:-}
EOF
# -D: in the foreground of a background process, so that $! is the daemon; 9>&-: a
# daemon left running (this script killed outright) does not hold the lock
slurmctld -D -c -f "${CONF}" >"${WORK}/log/slurmctld.out" 2>&1 9>&- &
STARTED_PIDS+=($!); STARTED_NAMES+=(slurmctld)
slurmd -D -f "${CONF}" -N "${NODE}" >"${WORK}/log/slurmd.out" 2>&1 9>&- &
STARTED_PIDS+=($!); STARTED_NAMES+=(slurmd)
state=""
for ((i = 0; i < 300; i++)); do
    for ((j = 0; j < ${#STARTED_PIDS[@]}; j++)); do
        kill -0 "${STARTED_PIDS[j]}" 2>/dev/null \
            || die "${STARTED_NAMES[j]} exited (see ${WORK}/log/${STARTED_NAMES[j]}.out)"
    done
    state="$(sinfo -h -n "${NODE}" -o %T 2>/dev/null || true)"
    [[ "${state}" == idle ]] && break
    sleep 0.1
done
[[ "${state}" == idle ]] || die "node ${NODE} is '${state}', not idle, after 30 s"
echo "node ${NODE}: CPUs=${CPUS} RealMemory=${MEM} MB, ${state}"

# ------------------------------------------------------------------ 3. the workflow
cd "${REPO}"
if [[ -n "${EXEC}" ]]; then
    step "run: ${EXEC}"
    bash -c "${EXEC}"
    exit
fi
max_jobid() { squeue -h -t all -o %i | sort -n | tail -n 1; }

if [[ "${HPFEBE_SLURM_ORPHAN_CHECK:-0}" == 1 ]]; then
    # kill -9 of the main Snakemake while jobs run: no job may write (or remove) a result
    # file afterwards (results/logs/ excepted: a stopping job logs why).
    step "orphan check: kill -9 of the main Snakemake"
    setsid snakemake "${SNAKEMAKE_ARGS[@]}" --forceall >"${WORK}/log/orphan.log" 2>&1 &
    main=$!; ORPHAN_MAIN=${main}
    for ((i = 0; i < 600; i++)); do        # two jobs past numba_cache, 3 s into their run
        n="$(squeue -h -t R -o '%k %M' | grep -v 'numba_cache\|ch4_adaptive_fefe' \
            | awk '$2 >= "0:03"' | wc -l || true)"
        ((n >= 2)) && break
        if ! kill -0 "${main}" 2>/dev/null; then
            cat "${WORK}/log/orphan.log" >&2; die "the run ended before two jobs ran"
        fi
        sleep 0.5
    done
    ((n >= 2)) || die "no job ran within 5 min"
    find results -type f -not -path 'results/logs/*' | sort >"${WORK}/files_before"
    touch "${WORK}/killed"
    kill -9 "${main}"; ORPHAN_MAIN=""
    for ((i = 0; i < 240; i++)); do        # every job ends by itself (nothing scancels)
        [[ -z "$(squeue -h -o %i)" ]] && break
        sleep 0.5
    done
    [[ -z "$(squeue -h -o %i)" ]] || { squeue >&2; die "jobs queued 2 min after the kill"; }
    echo "queue empty $((i / 2)) s after the kill"
    find results -type f -not -path 'results/logs/*' | sort >"${WORK}/files_after"
    written="$(find results -type f -not -path 'results/logs/*' -newer "${WORK}/killed" \
        | head -n 10)"
    removed="$(comm -23 "${WORK}/files_before" "${WORK}/files_after" | head -n 10)"
    [[ -z "${written}${removed}" ]] || die "jobs changed results/ after the kill:
${written}
${removed:+removed: ${removed}}"
    echo "no result file written or removed after the kill"
    snakemake "${SNAKEMAKE_ARGS[@]}" --unlock >/dev/null 2>&1
fi

step "quick workflow through SLURM"
LOG1="${WORK}/log/run1.log"
snakemake "${SNAKEMAKE_ARGS[@]}" --forceall 2>&1 | tee "${LOG1}"
submitted="$(grep -c 'has been submitted with SLURM jobid' "${LOG1}" || true)"
((submitted > 0)) || die "the first call submitted no SLURM job"
echo "${submitted} SLURM jobs submitted"

step "report present"
test -s report/index.html || die "no report/index.html"
test -s report/report.md || die "no report/report.md"
grep -q "hpfebe: reproduction report" report/index.html \
    || die "report/index.html is not the report"
[[ "$(find report/index.html -newer "${WORK}/started")" ]] \
    || die "report/index.html was not rebuilt"

step "second call plans nothing (dry run)"
if ! out="$(snakemake "${SNAKEMAKE_ARGS[@]}" -n 2>&1)" \
        || ! grep -q "Nothing to be done" <<<"${out}"; then
    printf '%s\n' "${out}" >&2; die "the dry run failed or plans jobs"
fi

step "second call submits nothing"
before="$(max_jobid)"
LOG2="${WORK}/log/run2.log"
if ! snakemake "${SNAKEMAKE_ARGS[@]}" >"${LOG2}" 2>&1 || ! grep -q "Nothing to be done" "${LOG2}"
then
    cat "${LOG2}" >&2; die "the second call failed or ran jobs"
fi
after="$(max_jobid)"
[[ "${before}" == "${after}" ]] || die "the second call submitted SLURM jobs (${before} -> ${after})"
echo "no job submitted (last SLURM job id ${after})"
