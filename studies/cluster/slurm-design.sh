#!/bin/bash
# Run the islands of a `grainchain design` search as a SLURM job array: one array task per
# island, all writing their journals into the same directory on a shared file system; then merge
# once every task has finished (the outputs are written from every island's journal).
#
#   sbatch --parsable --array=1-8 studies/cluster/slurm-design.sh designs/multi-material.toml out/design-mm 8
#   sbatch --dependency=afterok:<array job id> --wrap \
#       "grainchain design designs/multi-material.toml --merge --out out/design-mm"
#
# The third argument N is the number of islands and must be given (a rerun of one failed task,
# `sbatch --array=2 ... 8`, must still run island 2/8). Island K searches with seed + K - 1 and
# every task passes --resume, so a rerun replays its island and runs only the designs its killed
# predecessor had not journalled. Results do not depend on the cores: the merged outputs are
# byte-identical to islands run one after another on one machine (studies/cluster/test-slurm.sh
# checks this on a real one-node SLURM cluster).
#SBATCH --job-name=grainchain-design
#SBATCH --cpus-per-task=4
#SBATCH --time=04:00:00
#SBATCH --output=grainchain-design-%A_%a.log
set -euo pipefail
usage="usage: sbatch --array=1-N slurm-design.sh DESIGN.toml OUT_DIR N (N: the number of islands)"
DESIGN=${1:?$usage}
OUT=${2:?$usage}
N=${3:?$usage}
K=${SLURM_ARRAY_TASK_ID:?run through sbatch --array}
if ! [[ $N =~ ^[1-9][0-9]*$ && $K =~ ^[0-9]+$ ]] || ((K < 1 || K > N)); then
  echo "slurm-design.sh: array task $K is not an island of N = $N (array indices run 1..N)" >&2
  exit 2
fi
grainchain design "$DESIGN" --out "$OUT" --shard "$K/$N" --threads "${SLURM_CPUS_PER_TASK:-1}" --resume
