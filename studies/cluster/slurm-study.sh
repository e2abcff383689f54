#!/bin/bash
# Run a grainchain study as a SLURM job array: one array task per shard, all writing member files
# into the same directory on a shared file system; then merge once every task has finished.
#
#   sbatch --array=1-10 studies/cluster/slurm-study.sh studies/long.toml out/study-long
#   # when the array is done (or chain it: sbatch --dependency=afterok:<array job id> ...):
#   grainchain study studies/long.toml --merge --out out/study-long
#
# Each task runs the jobs j with j mod N = K - 1 (K = SLURM_ARRAY_TASK_ID, N = the array size),
# on the cores SLURM gives it. Results do not depend on N, K or the cores: merged shards equal a
# single-machine run bit for bit (validation/study.rs). A task that was killed can be run again
# with --resume: members already written (for the same sweep settings) are kept.
#SBATCH --job-name=grainchain-study
#SBATCH --cpus-per-task=4
#SBATCH --time=04:00:00
#SBATCH --output=grainchain-study-%A_%a.log
set -euo pipefail
SWEEP=${1:?usage: sbatch --array=1-N slurm-study.sh SWEEP.toml OUT_DIR}
OUT=${2:?usage: sbatch --array=1-N slurm-study.sh SWEEP.toml OUT_DIR}
K=${SLURM_ARRAY_TASK_ID:?run through sbatch --array}
N=${SLURM_ARRAY_TASK_COUNT:?run through sbatch --array}
grainchain study "$SWEEP" --out "$OUT" --shard "$K/$N" --threads "${SLURM_CPUS_PER_TASK:-1}" --resume
