# A throwaway single-node Slurm for the cluster tests (sourced after ../lib.sh).
#   slurm_start [CPUS]   munged + slurmctld + slurmd from Debian's slurm-wlm and munge,
#                        as root, without systemd, all state under $TMP/slurm, on free
#                        ports of 127.0.0.1; returns when sinfo shows the node idle.
#                        Exports SLURM_CONF (the clients find this cluster through it).
#                        Where it cannot start: prints "SKIP: why" and exits 77
#                        (ctest SKIP_RETURN_CODE), or fails when SCANLOD_REQUIRE_SLURM=1.
#   slurm_sbatch ARGS... sbatch --parsable, with the mark below in the job's environment.
# At exit every job is cancelled and every process of this cluster ended (by pid), before
# lib.sh removes $TMP.
# A requeued job waits cred_expire seconds before it may start again (the credentials of
# the killed run are revoked that long): 10 here, Slurm's default is 120; and the
# scheduler looks at pending jobs every 2 s (default 60).
# The node has CPUS (default 4) CPUs whatever the machine has (config_overrides), so that
# small test arrays run all their tasks at once; the scheduler never starts more.

SLURM_DIR=$TMP/slurm
# Every process of this cluster carries this variable (daemons, step daemons, jobs): the
# teardown ends exactly those, however a job got stuck.
SLURM_MARK="scanlod-test-slurm-$$-$RANDOM"
slurm_pids=()

slurm_skip() {
  if [ "${SCANLOD_REQUIRE_SLURM:-0}" = 1 ]; then
    echo "FAIL: Slurm cannot start here: $*" >&2
    exit 1
  fi
  echo "SKIP: Slurm cannot start here: $*"
  exit 77
}

# slurm_wait SECONDS DESCRIPTION COMMAND...: polls COMMAND every 0.2 s until it succeeds.
slurm_wait() {
  local deadline=$((SECONDS + $1)) what=$2; shift 2
  until "$@" >/dev/null 2>&1; do
    [ "$SECONDS" -lt "$deadline" ] || { echo "timed out waiting for $what" >&2; return 1; }
    sleep 0.2
  done
}

slurm_free_port() { # a TCP port nothing listens on, away from the well-known ones
  local p i
  for i in $(seq 50); do
    p=$((20000 + RANDOM % 30000))
    [ -z "$(ss -Htln "sport = :$p" 2>/dev/null)" ] && [ -z "$(ss -Htln "sport = :$((p + 1))" 2>/dev/null)" ] &&
      { echo "$p"; return 0; }
  done
  return 1
}

slurm_logs() { # the daemons' logs, for a failure message
  local f
  for f in "$SLURM_DIR"/log/*.log "$SLURM_DIR"/log/*.out; do
    [ -f "$f" ] && { echo "--- $f"; tail -n 15 "$f"; }
  done
}

slurm_marked_pids() {
  local f
  for f in /proc/[0-9]*/environ; do
    grep -qsz "^SCANLOD_SLURM_MARK=$SLURM_MARK\$" "$f" && { f=${f#/proc/}; echo "${f%/environ}"; }
  done
  return 0
}

slurm_stop() {
  if [ -n "${SLURM_CONF:-}" ] && [ -f "$SLURM_CONF" ]; then
    # A job that requeues itself comes back pending: cancel until none is left.
    local deadline=$((SECONDS + 40))
    while [ "$SECONDS" -lt "$deadline" ]; do
      local jobs
      jobs=$(timeout 10 squeue -h -o %i 2>/dev/null) || break
      [ -z "$jobs" ] && break
      timeout 10 scancel $jobs 2>/dev/null
      sleep 0.5
    done
  fi
  local p
  for p in "${slurm_pids[@]}"; do kill -TERM "$p" 2>/dev/null; done
  for p in "${slurm_pids[@]}"; do
    timeout 10 tail --pid="$p" -f /dev/null 2>/dev/null
  done
  # Whatever is left of this cluster (step daemons, job processes) ends here.
  for p in $(slurm_marked_pids); do kill -KILL "$p" 2>/dev/null; done
  return 0
}

slurm_start() {
  local cpus=${1:-4} cmd
  [ "$(id -u)" -eq 0 ] || slurm_skip "not root (slurmd runs jobs as their users)"
  for cmd in munged slurmctld slurmd sbatch scontrol sinfo squeue scancel ss; do
    command -v "$cmd" >/dev/null || slurm_skip "no $cmd (scripts/install-deps.sh installs slurm-wlm and munge)"
  done
  local host
  host=$(hostname -s)
  mkdir -p "$SLURM_DIR"/{munge,state,spool,log}
  chmod 755 "$SLURM_DIR/munge"
  # munged refuses a key readable by others; 1 KiB of random bytes is a valid key.
  head -c 1024 /dev/urandom >"$SLURM_DIR/munge/munge.key"
  chmod 400 "$SLURM_DIR/munge/munge.key"
  local ctld_port d_port
  ctld_port=$(slurm_free_port) && d_port=$(slurm_free_port) || slurm_skip "no free TCP port"
  export SLURM_CONF=$SLURM_DIR/slurm.conf
  cat >"$SLURM_CONF" <<EOF
ClusterName=scanlodtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$d_port
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$SLURM_DIR/munge/socket,cred_expire=10
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$SLURM_DIR/state
SlurmdSpoolDir=$SLURM_DIR/spool
SlurmctldPidFile=$SLURM_DIR/slurmctld.pid
SlurmdPidFile=$SLURM_DIR/slurmd.pid
SlurmctldLogFile=$SLURM_DIR/log/slurmctld.log
SlurmdLogFile=$SLURM_DIR/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$SLURM_DIR/log/jobcomp.txt
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
SchedulerParameters=sched_interval=2
MpiDefault=none
ReturnToService=2
SlurmdParameters=config_overrides
KillWait=15
MinJobAge=3600
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=4000 State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
  cleanup_hooks=(slurm_stop "${cleanup_hooks[@]}")
  export SCANLOD_SLURM_MARK=$SLURM_MARK
  munged -F -f --socket="$SLURM_DIR/munge/socket" --key-file="$SLURM_DIR/munge/munge.key" \
    --log-file="$SLURM_DIR/log/munged.log" --pid-file="$SLURM_DIR/munge/munged.pid" \
    --seed-file="$SLURM_DIR/munge/seed" >"$SLURM_DIR/log/munged.out" 2>&1 &
  slurm_pids+=($!)
  slurm_up 15 "munged's socket" test -S "$SLURM_DIR/munge/socket" ||
    slurm_skip "munged did not start: $(slurm_logs)"
  slurmctld -D -i -f "$SLURM_CONF" >"$SLURM_DIR/log/slurmctld.out" 2>&1 &
  slurm_pids+=($!)
  slurm_up 30 "slurmctld" timeout 5 scontrol ping ||
    slurm_skip "slurmctld did not answer: $(slurm_logs)"
  slurmd -D -f "$SLURM_CONF" -N "$host" >"$SLURM_DIR/log/slurmd.out" 2>&1 &
  slurm_pids+=($!)
  unset SCANLOD_SLURM_MARK # the test's own shell is not part of the cluster
  slurm_up 60 "the node to be idle" slurm_node_idle ||
    slurm_skip "slurmd did not register: $(timeout 5 sinfo 2>&1) $(slurm_logs)"
}

# slurm_up SECONDS DESCRIPTION COMMAND...: slurm_wait, given up at once when the daemon
# started last has exited.
slurm_up() {
  local deadline=$((SECONDS + $1)) what=$2 daemon=${slurm_pids[-1]}; shift 2
  until "$@" >/dev/null 2>&1; do
    kill -0 "$daemon" 2>/dev/null || { echo "waiting for $what: the daemon exited" >&2; return 1; }
    [ "$SECONDS" -lt "$deadline" ] || { echo "timed out waiting for $what" >&2; return 1; }
    sleep 0.2
  done
}

slurm_node_idle() {
  [ "$(timeout 5 sinfo -h -N -o %t 2>/dev/null)" = idle ]
}

slurm_sbatch() {
  env SCANLOD_SLURM_MARK="$SLURM_MARK" timeout 30 sbatch --parsable "$@"
}
