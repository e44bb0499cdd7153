#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for trying the scripts in deploy/slurm and for their
# test: munged, slurmctld and slurmd from Debian's packages, without systemd, with every file under
# one state directory. Run as root (slurmd starts jobs as their submitting user).
#
#   deploy/slurm/local-cluster.sh start STATE_DIR   writes STATE_DIR/slurm.conf, starts the daemons,
#                                                   waits for the node to be idle and prints
#                                                   "export SLURM_CONF=STATE_DIR/slurm.conf"
#   deploy/slurm/local-cluster.sh stop STATE_DIR    stops them
#
# The configuration is PLATFORM-NOTES' working single-node one: proctrack/linuxproc, task/none,
# select/cons_tres, MpiDefault=pmix, no accounting, the node's real CPU count and memory. Job
# credentials live 20 s instead of 120 (GONOGO_SLURM_CRED_EXPIRE_S): Slurm holds a requeued job
# that long before it starts it again.
set -euo pipefail
action=${1:?usage: local-cluster.sh start|stop STATE_DIR}
state=$(mkdir -p "${2:?usage: local-cluster.sh start|stop STATE_DIR}" && cd "$2" && pwd)
conf=$state/slurm.conf
node=$(hostname -s)

stop() {
  for d in slurmd slurmctld; do
    [ -s "$state/$d.pid" ] && kill "$(cat "$state/$d.pid")" 2>/dev/null || true
  done
  for _ in $(seq 1 50); do
    pgrep -f "slurm(ctld|d) .*$conf" >/dev/null || break
    sleep 0.2
  done
  [ -s "$state/munged.pid" ] && kill "$(cat "$state/munged.pid")" 2>/dev/null || true
  rm -f "$state"/*.pid
}

if [ "$action" = stop ]; then
  stop
  exit 0
fi
[ "$action" = start ] || { echo "local-cluster.sh: unknown action '$action' (start or stop)" >&2; exit 2; }
[ "$(id -u)" -eq 0 ] || { echo "local-cluster.sh: run as root (slurmd starts jobs as their users)" >&2; exit 2; }

cpus=$(nproc)
memory_mb=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 512 ))
mkdir -p "$state/spool/ctld" "$state/spool/d" "$state/munge" "$state/log"
chmod 0755 "$state"
chown munge:munge "$state/munge"
chmod 0755 "$state/munge"
cat > "$conf" <<CONF
ClusterName=gonogo-local
SlurmctldHost=$node(127.0.0.1)
SlurmUser=root
SlurmctldPort=${GONOGO_SLURMCTLD_PORT:-6817}
SlurmdPort=${GONOGO_SLURMD_PORT:-6818}
AuthType=auth/munge
AuthInfo=socket=$state/munge/munge.socket,cred_expire=${GONOGO_SLURM_CRED_EXPIRE_S:-20}
StateSaveLocation=$state/spool/ctld
SlurmdSpoolDir=$state/spool/d
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/log/slurmctld.log
SlurmdLogFile=$state/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=pmix
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
ReturnToService=2
KillWait=30
MinJobAge=3600
SchedulerType=sched/backfill
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory_mb State=UNKNOWN
PartitionName=debug Nodes=$node Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
CONF

stop
# munged as its own user, on a socket in the state directory (no /run/munge needed).
runuser -u munge -- /usr/sbin/munged --socket="$state/munge/munge.socket" \
  --pid-file="$state/munge/munged.pid" --log-file="$state/munge/munged.log" --seed-file="$state/munge/seed" \
  --force
cp "$state/munge/munged.pid" "$state/munged.pid"
SLURM_CONF=$conf /usr/sbin/slurmctld -f "$conf"
SLURM_CONF=$conf /usr/sbin/slurmd -f "$conf"
for _ in $(seq 1 150); do
  state_now=$(SLURM_CONF=$conf sinfo -h -N -o %T 2>/dev/null || true)
  [ "$state_now" = idle ] && break
  sleep 0.2
done
[ "$state_now" = idle ] || {
  echo "local-cluster.sh: the node did not become idle (state '${state_now:-none}'); logs in $state/log" >&2
  exit 1
}
echo "export SLURM_CONF=$conf"
