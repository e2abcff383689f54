#!/bin/bash
# Run studies/cluster/slurm-study.sh under a real SLURM: a one-node cluster on localhost.
#
#   cargo build --release && sudo bash studies/cluster/test-slurm.sh
#
# As root on a Debian machine without a running SLURM: installs slurm-wlm and munge with apt if
# missing, writes a slurm.conf for this one node (CPUs and memory from `slurmd -C`) into a
# private directory, starts munged (unless one runs), slurmctld and slurmd there, and stops what
# it started on exit. Nothing in /etc/slurm is written. Then, for studies/smoke.toml:
#
#   1. an array of 3 tasks of slurm-study.sh and the merge as a job chained on it
#      (--dependency=afterok), compared with a single-machine run of the same study;
#   2. a failed task: task 2 of a new array is cancelled, so the chained merge never runs
#      (DependencyNeverSatisfied); task 2 alone is rerun (--array=2, shard 2/3), a new merge
#      is chained on it, and the result is compared again;
#   3. a task killed part way: one member of shard 2 is deleted from the study of step 1, task 2
#      is rerun and keeps its 3 other members (--resume), merge, compare again;
#   4. a design search in islands: studies/cluster/design-small.toml as an array of 2 tasks of
#      slurm-design.sh and the merge chained on it, against the two islands run one after the
#      other on this machine and merged: every output file byte-identical, the journals the same
#      lines (each island's lines are appended as evaluations finish).
#
# "Compare": the same files; every member CSV, output CSV and SVG byte-identical (cmp); member
# JSONs identical apart from their "wall" field (and the checksum of their text, "json_fnv"); STUDY.md identical apart from its wall-time
# lines, which are printed. Exit status non-zero on any difference or failure.
#
# Environment: GRAINCHAIN (the binary, default ${CARGO_TARGET_DIR:-target}/release/grainchain),
# GRAINCHAIN_SLURM_DIR (work directory, default /tmp/grainchain-slurm-test; emptied at start),
# WAIT_TIMEOUT (seconds to wait for a job, default 120).
set -euo pipefail

GC=${GRAINCHAIN:-${CARGO_TARGET_DIR:-target}/release/grainchain}
[[ -x $GC ]] || {
  echo "test-slurm: no grainchain binary at $GC (cargo build --release, or set GRAINCHAIN)" >&2
  exit 1
}
GC=$(realpath "$GC")
cd "$(dirname "$0")/../.."
REPO=$PWD
DIR=${GRAINCHAIN_SLURM_DIR:-/tmp/grainchain-slurm-test}
WAIT_TIMEOUT=${WAIT_TIMEOUT:-120}
SWEEP=studies/smoke.toml
SHARDS=3
START=$SECONDS

say() { printf '\n== %s\n' "$*"; }
die() {
  echo "test-slurm: FAIL: $*" >&2
  exit 1
}
[[ $(id -u) == 0 ]] || die "run as root (installs packages, starts the SLURM daemons)"

# --- install -------------------------------------------------------------------------------
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null ||
  ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
  say "installing slurm-wlm and munge"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q
  apt-get install -y -q --no-install-recommends slurm-wlm munge
fi
[[ -s /etc/munge/munge.key ]] || {
  mungekey --create --keyfile=/etc/munge/munge.key
  chown munge:munge /etc/munge/munge.key
  chmod 600 /etc/munge/munge.key
}

# --- daemons -------------------------------------------------------------------------------
# Our daemons write pid files into $DIR/run; a leftover from an interrupted run is stopped first.
stop_pidfile() {
  local f=$1 pid
  [[ -s $f ]] || return 0
  pid=$(<"$f")
  if kill -0 "$pid" 2>/dev/null; then
    kill "$pid"
    for _ in $(seq 50); do
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.1
    done
  fi
  rm -f "$f"
}
STARTED_MUNGE=
stop_daemons() {
  stop_pidfile "$DIR/run/slurmd.pid"
  stop_pidfile "$DIR/run/slurmctld.pid"
  if [[ -n $STARTED_MUNGE ]]; then stop_pidfile /run/munge/munged.pid; fi
}
if [[ -d $DIR/run ]]; then stop_daemons; fi
if pgrep -x slurmctld >/dev/null || pgrep -x slurmd >/dev/null; then
  die "a slurmctld or slurmd not started by this script is running; stop it first"
fi
on_exit() {
  local rc=$?
  say "stopping the SLURM daemons"
  stop_daemons
  exit "$rc"
}
trap on_exit EXIT

rm -rf "$DIR"
mkdir -p "$DIR"/{etc,run,log,state,spool,bin,jobs}
# The jobs find grainchain on PATH (sbatch exports the submitting environment). A copy, so a
# cargo build during the test does not change the binary under the jobs.
cp "$GC" "$DIR/bin/grainchain"
export PATH="$DIR/bin:$PATH"
export SLURM_CONF="$DIR/etc/slurm.conf"

HOST=$(hostname -s)
NODE=$(slurmd -C | head -n 1) # NodeName=<host> CPUs=.. Boards=.. ... RealMemory=..
[[ $NODE == "NodeName=$HOST "* ]] || die "slurmd -C printed '$NODE'"
cat >"$SLURM_CONF" <<EOF
# One-node cluster on localhost for studies/cluster/test-slurm.sh.
ClusterName=grainchain-test
SlurmctldHost=$HOST(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/run/slurmctld.pid
SlurmdPidFile=$DIR/run/slurmd.pid
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
# Finished jobs stay visible to scontrol (there is no accounting database for sacct).
MinJobAge=3600
$NODE NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=test Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF

say "starting munged, slurmctld, slurmd"
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
  mkdir -p /run/munge /var/log/munge /var/lib/munge
  chown munge:munge /run/munge /var/log/munge /var/lib/munge
  runuser -u munge -- munged
  STARTED_MUNGE=1
fi
munge -n | unmunge >/dev/null || die "munge does not work"
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for i in $(seq 60); do
  state=$(sinfo -h -N -o %T 2>/dev/null || true)
  [[ $state == idle ]] && break
  ((i < 60)) || die "node not idle after 30 s (state '$state'); see $DIR/log"
  sleep 0.5
done
sinfo -N -o "%N %P %T %c %m"

# --- helpers ---------------------------------------------------------------------------------
# Wait until job (or array) $1 has left the queue; then every task must have state COMPLETED.
wait_done() {
  local id=$1 t0=$SECONDS states
  while squeue -h -j "$id" 2>/dev/null | grep -q .; do
    ((SECONDS - t0 < WAIT_TIMEOUT)) || die "job $id not done after $WAIT_TIMEOUT s: $(squeue -j "$id")"
    sleep 0.5
  done
  states=$(scontrol -o show job "$id" | grep -o 'JobState=[A-Z_]*' | sort | uniq -c | xargs)
  echo "job $id done after $((SECONDS - t0)) s: $states"
  if scontrol -o show job "$id" | grep -o 'JobState=[A-Z_]*' | grep -qv COMPLETED; then
    scontrol -o show job "$id" | grep -o 'JobId=[0-9]* \|ArrayTaskId=[0-9]*\|JobState=[A-Z_]*\|StdOut=[^ ]*' | xargs -n 4
    die "job $id: a task did not complete"
  fi
}
# Submit the array of slurm-study.sh for tasks $2 (e.g. 1-3) into $1; extra sbatch options after.
submit_array() {
  local out=$1 tasks=$2
  shift 2
  echo "+ sbatch --parsable --array=$tasks --cpus-per-task=1 $* studies/cluster/slurm-study.sh $SWEEP $out $SHARDS" >&2
  sbatch --parsable --chdir="$REPO" --array="$tasks" --cpus-per-task=1 --time=00:10:00 \
    --output="$DIR/jobs/study-%A_%a.log" "$@" \
    studies/cluster/slurm-study.sh "$SWEEP" "$out" "$SHARDS"
}
# Submit the merge of $1, chained on job $2 (the array or a rerun).
submit_merge() {
  echo "+ sbatch --parsable --dependency=afterok:$2 --wrap \"grainchain study $SWEEP --merge --out $1\"" >&2
  sbatch --parsable --chdir="$REPO" --cpus-per-task=1 --time=00:10:00 \
    --dependency="afterok:$2" --job-name=grainchain-merge --output="$DIR/jobs/merge-%j.log" \
    --wrap "grainchain study $SWEEP --merge --out $1"
}
show_logs() { tail -q -n +1 "$@" | grep -E '^(study|error|wrote|\()' | sed 's/^/  | /'; }

# Normalized views: member JSON without its "wall" value (nor its own checksum, `json_fnv`, of
# a text that holds the wall time); STUDY.md without the values of its
# wall-time lines (the "Sum of the members' wall times" line and the "wall per member (s)"
# column of the Cost table). Anything else that differs fails the comparison.
norm_json() { sed -E -e 's/^( *"wall": )[-+0-9.eE]+/\1<wall>/' -e 's/^( *"json_fnv": )"[0-9a-f]*"/\1<fnv>/' "$1"; }
norm_study() {
  awk -F' [|] ' -v OFS=' | ' '
    /^## / { cost = ($0 == "## Cost"); col = 0 }
    cost && /^Sum of the members.? wall times: / { sub(/: [0-9.]+ s/, ": <wall> s") }
    cost && /^[|]/ {
      if (!col) { for (i = 1; i <= NF; i++) if ($i ~ /^wall per member/) col = i }
      else if ($0 !~ /^[|]---/) { $col = "<wall>" }
    }
    { print }' "$1"
}
# manifest.json without the entry of STUDY.md (whose wall-time lines give it another size and
# checksum); every other file's size and checksum is compared.
norm_manifest() {
  awk '/"STUDY.md": \{/ { skip = 1; next } skip && /}/ { skip = 0; next } !skip { print }' "$1"
}
# The files of a study directory, without the lock files (dot files: a sharded run holds one per
# shard, a single-machine run one for the folder).
files_of() {
  (cd "$1" && find . -type f ! -name '.*' | sort)
}
# Compare study directory $2 with the single-machine run $1.
compare() {
  local a=$1 b=$2 f n_cmp=0 n_json=0 bad=0
  diff <(files_of "$a") <(files_of "$b") ||
    die "$b and $a hold different files"
  while read -r f; do
    case $f in
    ./members/*.json)
      diff -q <(norm_json "$a/$f") <(norm_json "$b/$f") >/dev/null || {
        diff <(norm_json "$a/$f") <(norm_json "$b/$f")
        echo "DIFFERS (apart from wall): $f"
        bad=1
      }
      n_json=$((n_json + 1))
      ;;
    ./manifest.json)
      diff <(norm_manifest "$a/$f") <(norm_manifest "$b/$f") || {
        echo "DIFFERS (apart from the entry of STUDY.md): $f"
        bad=1
      }
      ;;
    ./STUDY.md)
      diff <(norm_study "$a/$f") <(norm_study "$b/$f") || {
        echo "DIFFERS (apart from wall times): $f"
        bad=1
      }
      ;;
    *)
      cmp "$a/$f" "$b/$f" || bad=1
      n_cmp=$((n_cmp + 1))
      ;;
    esac
  done < <(files_of "$a")
  ((bad == 0)) || die "$b differs from the single-machine run $a"
  echo "compare $b with $a:"
  echo "  byte-identical (cmp): $n_cmp files:" \
    "$(cd "$b" && find . -type f -path './members/*.csv' | wc -l) member CSVs," \
    "$(cd "$b" && find . -maxdepth 1 -type f -name '*.csv' | wc -l) output CSVs," \
    "$(cd "$b" && find . -type f -name '*.svg' | wc -l) SVGs"
  echo "  identical apart from \"wall\": $n_json member JSONs (the wall time differs in" \
    "$(diff <(cat "$a"/members/*.json) <(cat "$b"/members/*.json) | grep -c '^< *"wall"') of them)"
  echo "  STUDY.md identical apart from these lines (wall times):"
  diff --unchanged-line-format= --old-line-format='    %dn < %L' --new-line-format='    %dn > %L' \
    "$a/STUDY.md" "$b/STUDY.md" || true
}

# --- the single-machine run ------------------------------------------------------------------
say "single-machine run"
grainchain study "$SWEEP" --out "$DIR/single" --threads 2 | sed 's/^/  | /'

# --- 1. array of 3 tasks, merge chained on it ------------------------------------------------
say "1. array of $SHARDS tasks and the chained merge"
A=$DIR/out-array
ARR=$(submit_array "$A" "1-$SHARDS")
MERGE=$(submit_merge "$A" "$ARR")
echo "sbatch --array=1-$SHARDS: job $ARR; merge job $MERGE (--dependency=afterok:$ARR)"
squeue -o "%i %j %T %r" -j "$ARR,$MERGE" || true
wait_done "$ARR"
wait_done "$MERGE"
show_logs "$DIR"/jobs/study-"$ARR"_*.log "$DIR/jobs/merge-$MERGE.log"
compare "$DIR/single" "$A"

# --- 2. a failed task: the merge never runs; rerun the task, chain a new merge ---------------
say "2. task 2 fails (cancelled): rerun it alone with --array=2"
B=$DIR/out-failed
ARR=$(submit_array "$B" "1-$SHARDS" --hold)
scancel "${ARR}_2"
MERGE=$(submit_merge "$B" "$ARR")
scontrol release "$ARR"
echo "array job $ARR with task 2 cancelled; merge job $MERGE (--dependency=afterok:$ARR)"
t0=$SECONDS
while squeue -h -j "$ARR" 2>/dev/null | grep -q .; do
  ((SECONDS - t0 < WAIT_TIMEOUT)) || die "array $ARR not done after $WAIT_TIMEOUT s"
  sleep 0.5
done
scontrol -o show job "$ARR" | grep -o 'ArrayTaskId=[0-9]*\|JobState=[A-Z_]*' | xargs -n 2 echo " "
t0=$SECONDS
until [[ $(squeue -h -j "$MERGE" -o %r 2>/dev/null) == DependencyNeverSatisfied ]]; do
  ((SECONDS - t0 < WAIT_TIMEOUT)) || die "merge job $MERGE: $(squeue -j "$MERGE" -o '%T %r')"
  sleep 0.5
done
squeue -j "$MERGE" -o "%i %j %T %r"
[[ ! -e $B/STUDY.md ]] || die "the merge ran although task 2 failed"
grainchain study "$SWEEP" --merge --out "$B" 2>&1 | sed 's/^/  | /' || true
scancel "$MERGE"
echo "scancel $MERGE; rerun of task 2:"
RERUN=$(submit_array "$B" 2)
MERGE=$(submit_merge "$B" "$RERUN")
echo "sbatch --array=2 ... $SHARDS: job $RERUN; merge job $MERGE (--dependency=afterok:$RERUN)"
wait_done "$RERUN"
wait_done "$MERGE"
show_logs "$DIR"/jobs/study-"$ARR"_*.log "$DIR"/jobs/study-"$RERUN"_*.log "$DIR/jobs/merge-$MERGE.log"
compare "$DIR/single" "$B"

# --- 3. a task killed part way: rerun with --resume keeps its members ------------------------
say "3. one member of shard 2 lost (task killed part way): rerun task 2, --resume keeps the rest"
rm -v "$A"/members/a-m1.{csv,json} # job 1: shard 2/3
RERUN=$(submit_array "$A" 2)
MERGE=$(submit_merge "$A" "$RERUN")
echo "sbatch --array=2 ... $SHARDS: job $RERUN; merge job $MERGE (--dependency=afterok:$RERUN)"
wait_done "$RERUN"
wait_done "$MERGE"
show_logs "$DIR"/jobs/study-"$RERUN"_*.log "$DIR/jobs/merge-$MERGE.log"
grep -q 'ran 1 of 12 members (3 kept' "$DIR"/jobs/study-"$RERUN"_2.log ||
  die "the rerun of task 2 did not keep its 3 other members"
compare "$DIR/single" "$A"

# --- 4. a design search in islands --------------------------------------------------------
say "4. design islands: an array of 2 tasks of slurm-design.sh and the chained merge"
# A 12-bead design made for this test: the cluster path is what is checked, not the search, and
# designs/steel-ptfe.toml's merge (its ten best designs' estimates, their bounds run on) took
# minutes in the merge job on one CPU.
DESIGN=studies/cluster/design-small.toml
DS=$DIR/design-single
for k in 1 2; do grainchain design "$DESIGN" --out "$DS" --shard "$k/2" --threads 1; done 2>&1 | sed 's/^/  | /'
t_merge=$SECONDS
grainchain design "$DESIGN" --out "$DS" --merge --threads 2 2>&1 | sed 's/^/  | /'
t_merge=$((SECONDS - t_merge))
DA=$DIR/design-array
echo "+ sbatch --parsable --array=1-2 --cpus-per-task=1 studies/cluster/slurm-design.sh $DESIGN $DA 2"
ARR=$(sbatch --parsable --chdir="$REPO" --array=1-2 --cpus-per-task=1 --time=00:10:00 \
  --output="$DIR/jobs/design-%A_%a.log" studies/cluster/slurm-design.sh "$DESIGN" "$DA" 2)
MERGE=$(sbatch --parsable --chdir="$REPO" --cpus-per-task=1 --time=00:10:00 \
  --dependency="afterok:$ARR" --job-name=grainchain-design-merge \
  --output="$DIR/jobs/design-merge-%j.log" --wrap "grainchain design $DESIGN --merge --out $DA")
echo "design array job $ARR; merge job $MERGE (--dependency=afterok:$ARR)"
wait_done "$ARR"
# The merge job does the local merge's work (the reported designs' error estimates, their bounds
# run on) on one CPU where the local merge had two: wait up to three times the local merge's
# time, and never less than the usual timeout.
wait_usual=$WAIT_TIMEOUT
WAIT_TIMEOUT=$((3 * t_merge > WAIT_TIMEOUT ? 3 * t_merge : WAIT_TIMEOUT))
wait_done "$MERGE"
WAIT_TIMEOUT=$wait_usual
tail -q -n 2 "$DIR"/jobs/design-"$ARR"_*.log "$DIR/jobs/design-merge-$MERGE.log" | sed 's/^/  | /'
diff <(files_of "$DS") <(files_of "$DA") || die "$DA and $DS hold different files"
n=0
while read -r f; do
  case $f in
  ./evaluations/island-?-of-2.csv)
    # The same lines: an island's evaluations are appended as they finish.
    cmp <(sort "$DS/$f") <(sort "$DA/$f") || die "$f: the journals differ"
    ;;
  *) cmp "$DS/$f" "$DA/$f" || die "$f differs from the islands run on this machine" ;;
  esac
  n=$((n + 1))
done < <(files_of "$DS")
echo "compare $DA with $DS: $n files the same ($(grep -c . "$DA/designs.csv") lines of designs.csv)"

say "OK: SLURM runs equal the single-machine run apart from wall times ($((SECONDS - START)) s)"
