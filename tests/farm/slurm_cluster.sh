# shellcheck shell=bash
# A one-node Slurm cluster on loopback for the farm test, sourced by slurm_farm_test.sh:
# munged with its own key and socket, slurmctld and slurmd with their own slurm.conf, state and
# logs, all in one temporary folder (proctrack/linuxproc, task/none: no cgroups). Needs root
# (the daemons run as root, SlurmUser=root) and Debian's slurm-wlm and munge.
#
#   cluster_start DIR CPUS   start it (SLURM_CONF exported for sbatch, squeue, ...)
#   cluster_stop             stop every daemon it started (the caller's EXIT trap)

cluster_pids=()

cluster_fail() {
  echo "FAIL: $*" >&2
  for log in "$cluster_dir"/*.log; do
    [ -f "$log" ] && { echo "--- $log" >&2; tail -n 20 "$log" >&2; }
  done
  exit 1
}

cluster_stop() {
  local pid
  for pid in "${cluster_pids[@]}"; do
    kill "$pid" 2>/dev/null || true
  done
  for pid in "${cluster_pids[@]}"; do
    timeout 20 tail --pid="$pid" -f /dev/null 2>/dev/null || kill -9 "$pid" 2>/dev/null || true
  done
  cluster_pids=()
}

cluster_start() {
  cluster_dir=$1
  local cpus=$2 host port memory
  # The machine's memory (MB), as a real node declares it: without it Slurm takes 1 MB and
  # refuses any --mem (README's --sbatch '--mem=4G').
  memory=$(awk '/^MemTotal:/ {print int($2 / 1024)}' /proc/meminfo)
  host=$(hostname -s)
  mkdir -p "$cluster_dir/state" "$cluster_dir/spool"
  chmod 700 "$cluster_dir"
  # munge: its own key, socket, pid, seed and log (a key of 1024 random bytes, mode 0400).
  head -c 1024 /dev/urandom >"$cluster_dir/munge.key"
  chmod 400 "$cluster_dir/munge.key"
  munged --force --foreground --socket="$cluster_dir/munge.socket" \
    --key-file="$cluster_dir/munge.key" --pid-file="$cluster_dir/munged.pid" \
    --seed-file="$cluster_dir/munged.seed" --log-file="$cluster_dir/munged.log" \
    >>"$cluster_dir/munged.log" 2>&1 &
  cluster_pids+=($!)
  timeout 20 bash -c "until [ -S '$cluster_dir/munge.socket' ]; do sleep 0.1; done" ||
    cluster_fail "munged did not start"
  # Two free-looking ports from the ephemeral range's far end (a clash fails the start, loudly).
  port=$((30000 + RANDOM % 20000))
  cat >"$cluster_dir/slurm.conf" <<CONF
ClusterName=spotfarm
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$cluster_dir/munge.socket
StateSaveLocation=$cluster_dir/state
SlurmdSpoolDir=$cluster_dir/spool
SlurmctldPidFile=$cluster_dir/slurmctld.pid
SlurmdPidFile=$cluster_dir/slurmd.pid
SlurmctldLogFile=$cluster_dir/slurmctld.log
SlurmdLogFile=$cluster_dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
SchedulerParameters=defer_batch
MpiDefault=none
ReturnToService=2
KillWait=5
InactiveLimit=0
MinJobAge=300
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=farm Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF=$cluster_dir/slurm.conf
  slurmctld -D -i -f "$SLURM_CONF" >>"$cluster_dir/slurmctld.log" 2>&1 &
  cluster_pids+=($!)
  slurmd -D -f "$SLURM_CONF" -N "$host" >>"$cluster_dir/slurmd.log" 2>&1 &
  cluster_pids+=($!)
  timeout 60 bash -c 'until sinfo -h -o %T 2>/dev/null | grep -qx idle; do sleep 0.5; done' ||
    cluster_fail "the node did not come up idle: $(sinfo 2>&1 | tr '\n' ' ')"
}
