#!/bin/bash
# mpi.sh -- a render split over MPI ranks is the render of one process, bit
# for bit, and a rank that dies stops the run without an image.
#
#   tests/mpi.sh BUILD_DIR MPI_BUILD_DIR      (make test-mpi)
#
# Skipped, with a message and status 0, when mpirun or the MPI build is not
# there (make mpi-deps installs OpenMPI). On one machine, ranks beyond the
# cores share them (--oversubscribe):
#   - chapter 09 (--spp, and --target-error: progressive) and chapter 13
#     (--one-path) on 1, 2 and 3 ranks, one or two threads each: the EXR is
#     the same bytes as the plain program's, and so are the counters;
#   - a run of 2 ranks whose rank 1 is killed after a checkpoint: non-zero
#     status, mpirun's message names rank 1, no image, the checkpoint kept;
#     resumed on 3 ranks it is the plain render, bit for bit;
#   - a mode that is not split (chapter 11) says so and exits 2 on 2 ranks;
#   - the twin: the same comparison tells another seed's image apart.
set -u
build=${1:?usage: mpi.sh BUILD_DIR MPI_BUILD_DIR}
mpi_build=${2:?usage: mpi.sh BUILD_DIR MPI_BUILD_DIR}
if ! command -v mpirun >/dev/null 2>&1 || [ ! -x "$mpi_build/bin/09-path-tracing" ]; then
    echo "mpi: skipped: no mpirun or no $mpi_build/bin/09-path-tracing (make mpi-deps, then make mpi)"
    exit 0
fi
# OpenMPI refuses to start as root unless told (CI containers run as root).
if [ "$(id -u)" = 0 ]; then export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1; fi
# In a container without ptrace rights, OpenMPI's single-copy transfers
# between processes of one machine fail; plain copies work everywhere.
export OMPI_MCA_btl_vader_single_copy_mechanism=none
work=$(mktemp -d "${TMPDIR:-/tmp}/mpi.XXXXXX")
trap 'rm -rf "$work"' EXIT
checks=0
failures=0
check() {
    local what=$1
    shift
    checks=$((checks + 1))
    if ! "$@"; then
        failures=$((failures + 1))
        echo "FAILED: $what"
    fi
}
same_counters() { # the counters files, less the lines that differ by design (and the commas JSON puts between)
    diff <(grep -Ev '"(seconds|command|threads|version|mpi_[a-z_]+)"' "$1" | sed 's/,$//') \
        <(grep -Ev '"(seconds|command|threads|version|mpi_[a-z_]+)"' "$2" | sed 's/,$//') >/dev/null
}
differ() { ! cmp -s "$1" "$2"; }
mpirun_n() { # mpirun_n N ARGS...
    local n=$1
    shift
    mpirun --oversubscribe -np "$n" "$@"
}

size="--width 48 --height 36 --quiet"
for case in "09-path-tracing --spp 16" "09-path-tracing --target-error 0.15" "13-production --one-path --spp 8"; do
    set -- $case
    prog=$1
    shift
    name=$(echo "$case" | tr -c 'a-z0-9\n' '_')
    "$build/bin/$prog" $size "$@" --threads 2 --out "$work/$name.exr" || { echo "FAILED: $case, one process"; continue; }
    for n in 1 2 3; do
        for threads in 1 2; do
            out=$work/$name-$n-$threads.exr
            mpirun_n $n "$mpi_build/bin/$prog" $size "$@" --threads $threads --out "$out" 2>"$work/log"
            check "$case on $n ranks of $threads threads exits 0 ($(head -3 "$work/log"))" [ $? = 0 ]
            check "$case on $n ranks of $threads threads is the one-process image, bit for bit" \
                cmp -s "$work/$name.exr" "$out"
            check "$case on $n ranks of $threads threads counts the same rays" \
                same_counters "$work/$name.counters.json" "${out%.exr}.counters.json"
        done
    done
done

# The twin: another seed, on 2 ranks, is another image.
mpirun_n 2 "$mpi_build/bin/09-path-tracing" $size --spp 16 --seed 2 --threads 1 --out "$work/seed2.exr"
check "the twin: another seed's image differs" differ "$work/09_path_tracing___spp_16.exr" "$work/seed2.exr"

# A rank killed in the middle: the run stops, no image, the checkpoint stays.
plain="--width 40 --height 32 --spp 1024 --quiet"
"$build/bin/09-path-tracing" $plain --threads 2 --out "$work/whole.exr"
mpirun --oversubscribe -np 2 "$mpi_build/bin/09-path-tracing" $plain --threads 1 --checkpoint-every 0 \
    --out "$work/killed.exr" >"$work/killed.log" 2>&1 &
mpirun_pid=$!
waited=0
while [ ! -s "$work/killed.checkpoint" ] && kill -0 $mpirun_pid 2>/dev/null && [ $waited -lt 600 ]; do
    sleep 0.05
    waited=$((waited + 1))
done
for pid in $(pgrep -P $mpirun_pid); do # the ranks are mpirun's children; rank 1 is the one whose environment says so
    if tr '\0' '\n' <"/proc/$pid/environ" 2>/dev/null | grep -qx 'OMPI_COMM_WORLD_RANK=1'; then kill -KILL "$pid"; fi
done
wait $mpirun_pid
status=$?
check "killing rank 1 ends the run with a non-zero status (was $status)" [ $status != 0 ]
check "mpirun names the rank that died ($(grep -i rank "$work/killed.log" | head -2))" \
    grep -q "rank 1 .*exited on signal 9" "$work/killed.log"
check "no image from the stopped run" [ ! -e "$work/killed.exr" ]
check "no temporary file is left" [ -z "$(find "$work" -name '*.tmp.*')" ]
check "the last checkpoint is kept" [ -s "$work/killed.checkpoint" ]
mpirun_n 3 "$mpi_build/bin/09-path-tracing" $plain --threads 1 --out "$work/killed.exr" \
    --resume "$work/killed.checkpoint"
check "resumed on 3 ranks, it is the one-process render, bit for bit" cmp -s "$work/whole.exr" "$work/killed.exr"

# What is not split says so.
mpirun_n 2 "$mpi_build/bin/11-bidirectional" --width 16 --height 12 --spp 1 --quiet --out "$work/bdpt.exr" \
    2>"$work/log"
status=$?
check "chapter 11 on 2 ranks refuses with status 2 (was $status)" [ $status = 2 ]
check "chapter 11 says why" grep -q "is not split across MPI ranks" "$work/log"

echo "mpi: $checks checks, $failures failed"
[ $failures = 0 ]
