#!/usr/bin/env bash
# A single-node SLURM cluster on this machine, then the reduced pipeline through the shipped
# SLURM profile: `snakemake --profile workflow/profiles/slurm --configfile workflow/config/ci.yaml`.
#
# For CI and for trying the profile without a cluster. Needs root and Debian's packages
# (`apt-get install -y slurm-wlm munge`; `.ci/slurm.sh --install` does it) and the SLURM
# executor plugin (`pip install -e ".[test]"` installs it). Configuration, state and logs go
# to $SLURM_DIR (default: a new temporary folder); the cluster configuration is written to
# /etc/slurm/slurm.conf (the SLURM executor plugin clears SLURM_* variables, SLURM_CONF
# included, inside jobs), unless a configuration not written by this script is there already.
# The daemons started here are stopped on exit. Usage, from the repository root:
#
#   .ci/slurm.sh [--install] [extra snakemake arguments, e.g. a target]
set -euo pipefail
cd "$(dirname "$0")/.."

if [[ "${1:-}" == "--install" ]]; then
    shift
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge
fi

SLURM_DIR="${SLURM_DIR:-$(mktemp -d /tmp/slurm.XXXXXX)}"
mkdir -p "$SLURM_DIR"/{state,spool,log,munge}
host="$(hostname -s)"
cpus="$(nproc)"
mem_mb="$(awk '/MemTotal/ {print int($2 / 1024 * 0.9)}' /proc/meminfo)"
SLURM_CONF=/etc/slurm/slurm.conf
MARK="# written by speckle's .ci/slurm.sh"
if [[ -e "$SLURM_CONF" ]] && ! grep -qF "$MARK" "$SLURM_CONF"; then
    echo "$SLURM_CONF exists and was not written by $0: not touching it" >&2
    exit 1
fi
mkdir -p /etc/slurm
cat > "$SLURM_CONF" <<EOF
$MARK
ClusterName=speckle
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
StateSaveLocation=$SLURM_DIR/state
SlurmdSpoolDir=$SLURM_DIR/spool
SlurmctldPidFile=$SLURM_DIR/slurmctld.pid
SlurmdPidFile=$SLURM_DIR/slurmd.pid
SlurmctldLogFile=$SLURM_DIR/log/slurmctld.log
SlurmdLogFile=$SLURM_DIR/log/slurmd.log
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
# keep finished jobs visible to squeue long enough for Snakemake's status queries
MinJobAge=600
NodeName=$host CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF

pids=()
stop() {
    for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
    wait 2>/dev/null || true
}
trap stop EXIT

# munge: the key from the package (created on install), socket and state in $SLURM_DIR
munge_sock="$SLURM_DIR/munge/munge.socket"
munged --foreground --force --socket="$munge_sock" \
    --pid-file="$SLURM_DIR/munge/munged.pid" --log-file="$SLURM_DIR/log/munged.log" \
    --seed-file="$SLURM_DIR/munge/munged.seed" &
pids+=($!)
# SLURM finds munge's socket through its AuthInfo
echo "AuthInfo=socket=$munge_sock" >> "$SLURM_CONF"
sleep 1
slurmctld -D -f "$SLURM_CONF" &
pids+=($!)
slurmd -D -f "$SLURM_CONF" &
pids+=($!)

for _ in $(seq 60); do
    if sinfo -h -o %T 2>/dev/null | grep -q idle; then break; fi
    sleep 1
done
sinfo
srun -N1 -n1 true  # the cluster runs a job

start=$(date +%s)
# This cluster has no accounting database (slurmdbd), so job states come from squeue
# (finished jobs stay listed for MinJobAge); a real cluster needs no such option.
snakemake "$@" --profile workflow/profiles/slurm --slurm-status-command squeue \
    --configfile workflow/config/ci.yaml
echo "reduced pipeline through SLURM: $(( $(date +%s) - start )) s wall"
