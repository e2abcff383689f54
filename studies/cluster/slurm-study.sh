#!/bin/bash
# Run a grainchain study as a SLURM job array: one array task per shard, all writing member files
# into the same directory on a shared file system; then merge once every task has finished.
#
#   sbatch --parsable --array=1-10 studies/cluster/slurm-study.sh studies/long.toml out/study-long 10
#   sbatch --dependency=afterok:<array job id> --wrap \
#       "grainchain study studies/long.toml --merge --out out/study-long"
#
# The third argument N is the study's shard count and must be given: array task K runs shard K/N,
# the jobs j with j mod N = K - 1, on the cores SLURM gives it. N is not taken from the array
# (SLURM_ARRAY_TASK_COUNT) because rerunning one failed task, `sbatch --array=2 ... 10`, is an
# array of 1 task that must still run shard 2/10. Every task passes --resume, so a rerun keeps
# the members its killed predecessor already wrote (for the same sweep settings) and runs the
# rest. Results do not depend on N, K or the cores: merged shards give the same member files and
# output tables as a single-machine run, byte for byte; only the wall times differ (the "wall"
# field of each member JSON, and in STUDY.md the "Sum of the members' wall times" line and the
# "wall per member (s)" column of the Cost table). studies/cluster/test-slurm.sh checks this on a
# real one-node SLURM cluster.
#SBATCH --job-name=grainchain-study
#SBATCH --cpus-per-task=4
#SBATCH --time=04:00:00
#SBATCH --output=grainchain-study-%A_%a.log
set -euo pipefail
usage="usage: sbatch --array=1-N slurm-study.sh SWEEP.toml OUT_DIR N (N: shard count of the study)"
SWEEP=${1:?$usage}
OUT=${2:?$usage}
N=${3:?$usage}
K=${SLURM_ARRAY_TASK_ID:?run through sbatch --array}
if ! [[ $N =~ ^[1-9][0-9]*$ && $K =~ ^[0-9]+$ ]] || ((K < 1 || K > N)); then
  echo "slurm-study.sh: array task $K is not a shard of N = $N (array indices run 1..N)" >&2
  exit 2
fi
grainchain study "$SWEEP" --out "$OUT" --shard "$K/$N" --threads "${SLURM_CPUS_PER_TASK:-1}" --resume
