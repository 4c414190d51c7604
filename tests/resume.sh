#!/bin/bash
# resume.sh -- a long render stopped by a signal and resumed from its last
# checkpoint makes the image the uninterrupted render makes, bit for bit.
#
#   tests/resume.sh BUILD_DIR        (run by `make test`; needs no MPI)
#
# With chapter 09's program, checkpoints after every pass (--checkpoint-every 0):
#   - a plain render (--spp), stopped by SIGTERM after its first checkpoint:
#     status 143, the previous image untouched, no temporary file left, the
#     checkpoint kept; resumed on another thread count, the EXR is the same
#     bytes as the uninterrupted render's, and the checkpoint is gone;
#   - a progressive render (--target-error), stopped by SIGINT: the same;
#   - a checkpoint of another render (seed, size, spp, scene file, another
#     flag) or not a checkpoint at all is refused with status 1 and a
#     message naming what differs, and nothing is written;
#   - a progressive render of hours is announced before it starts, one of
#     a moment is not;
#   - a checkpoint whose state is changed by one byte (one pixel's random
#     stream) is refused as damaged (its checksum), and nothing is written;
#     its twin, the same checkpoint unchanged, resumed above. (That such a
#     change would make another image, so that the bit-for-bit comparison
#     can fail, is test_resume's twin, which changes the streams in memory.)
set -u
build=${1:?usage: resume.sh BUILD_DIR}
program=$build/bin/09-path-tracing
scene=$(dirname "$0")/../chapters/09-path-tracing/scenes/cornell.scene
work=$(mktemp -d "${TMPDIR:-/tmp}/resume.XXXXXX")
trap 'rm -rf "$work"' EXIT
checks=0
failures=0

check() { # check DESCRIPTION COMMAND...: one check, reported when it fails
    local what=$1
    shift
    checks=$((checks + 1))
    if ! "$@"; then
        failures=$((failures + 1))
        echo "FAILED: $what"
    fi
}

# Starts "$@" in the background, waits until FILE exists, then sends SIGNAL;
# the status of the stopped run goes into $stopped_status.
stop_after_checkpoint() {
    local file=$1 signal=$2
    shift 2
    # SIGINT as a terminal's Ctrl-C delivers it: a background job of a
    # script starts with SIGINT ignored, and so does everything a runner
    # started in the background (a CI job, nohup); env puts it back.
    set -m
    env --default-signal=INT "$@" 2>"$work/stopped.log" &
    local pid=$! waited=0
    set +m
    while [ ! -s "$file" ] && kill -0 "$pid" 2>/dev/null && [ $waited -lt 600 ]; do
        sleep 0.05
        waited=$((waited + 1))
    done
    kill "-$signal" "$pid" 2>/dev/null
    wait "$pid"
    stopped_status=$?
}

size="--width 40 --height 32"
plain="$size --spp 1024 --quiet"
progressive="$size --target-error 0.04 --quiet"

# The uninterrupted renders.
"$program" $plain --threads 2 --out "$work/whole.exr" || { echo "FAILED: the uninterrupted render"; exit 1; }
"$program" $progressive --threads 2 --out "$work/whole-progressive.exr" ||
    { echo "FAILED: the uninterrupted progressive render"; exit 1; }

# A plain render, stopped by SIGTERM after a checkpoint, then resumed.
printf 'the previous image\n' > "$work/plain.exr"
stop_after_checkpoint "$work/plain.checkpoint" TERM "$program" $plain --threads 1 --checkpoint-every 0 \
    --out "$work/plain.exr"
check "SIGTERM ends the render with status 143 (was $stopped_status)" [ "$stopped_status" = 143 ]
check "the previous image is left as it was" grep -q 'the previous image' "$work/plain.exr"
check "no temporary file is left" [ -z "$(find "$work" -name '*.tmp.*')" ]
check "the checkpoint is kept" [ -s "$work/plain.checkpoint" ]
cp "$work/plain.checkpoint" "$work/kept.checkpoint"
check "resuming exits 0" "$program" $plain --threads 2 --out "$work/plain.exr" --resume "$work/plain.checkpoint"
check "the resumed render is the uninterrupted one, bit for bit" cmp -s "$work/whole.exr" "$work/plain.exr"
check "the checkpoint is removed once the image is written" [ ! -e "$work/plain.checkpoint" ]

# A progressive render, stopped by SIGINT (Ctrl-C), then resumed.
stop_after_checkpoint "$work/progressive.checkpoint" INT "$program" $progressive --threads 1 --checkpoint-every 0 \
    --out "$work/progressive.exr"
check "SIGINT ends the progressive render with status 130 (was $stopped_status)" [ "$stopped_status" = 130 ]
check "no image from the stopped progressive render" [ ! -e "$work/progressive.exr" ]
cp "$work/progressive.checkpoint" "$work/kept-progressive.checkpoint"
check "resuming the progressive render exits 0" \
    "$program" $progressive --threads 2 --out "$work/progressive.exr" --resume "$work/progressive.checkpoint"
check "the resumed progressive render is the uninterrupted one, bit for bit" \
    cmp -s "$work/whole-progressive.exr" "$work/progressive.exr"

# Checkpoints of another render are refused, naming what differs.
refused() { # refused CHECKPOINT WORDS FLAGS...: status 1, WORDS in the message, no image
    local from=$1 word=$2
    shift 2
    cp "$from" "$work/other.checkpoint"
    "$program" "$@" --quiet --out "$work/refused.exr" --resume "$work/other.checkpoint" 2>"$work/refused.log"
    local status=$?
    [ $status = 1 ] && grep -q -- "$word" "$work/refused.log" && [ ! -e "$work/refused.exr" ] ||
        { echo "  status $status: $(cat "$work/refused.log")"; return 1; }
}
kept=$work/kept.checkpoint
check "another seed is refused" refused "$kept" "seed is 1, this render's 2" $size --spp 1024 --seed 2
check "another size is refused" refused "$kept" "size is 40x32, this render's 48x32" --width 48 --height 32 --spp 1024
check "another spp is refused" refused "$kept" "spp is 1024, this render's 512" $size --spp 512
check "another integrator is refused" refused "$kept" "other flags are '', this render's '--integrator mis'" \
    $size --spp 1024 --integrator mis
check "another scene is refused" refused "$kept" "scene is built-in, this render's $scene" $size --spp 1024 \
    --scene "$scene"
check "a progressive render's checkpoint is refused by a plain render" \
    refused "$work/kept-progressive.checkpoint" "of a progressive render, this is a render one" $size --spp 1024
printf 'not a checkpoint\n' > "$work/junk.checkpoint"
check "a file that is not a checkpoint is refused" refused "$work/junk.checkpoint" "not a checkpoint" $plain

# One byte of one pixel's random stream changed: refused as damaged.
cp "$work/kept.checkpoint" "$work/changed.checkpoint"
checksum_line=26 # "checksum " and 16 hex digits and a newline, after the state
offset=$(($(stat -c %s "$work/changed.checkpoint") - checksum_line - 88 * (40 * 32 - (40 * 16 + 20)))) # pixel (20, 16)
printf '\x5a' | dd of="$work/changed.checkpoint" bs=1 seek=$offset conv=notrunc status=none
check "a checkpoint with one byte changed is refused as damaged" \
    refused "$work/changed.checkpoint" "damaged: what it holds does not match its checksum" $plain
not_grep() { ! grep -q "$1" "$2"; }

# A progressive render that would take far more than a minute says so
# before it starts (the pilot's error at 16 spp: 0.001 needs some 10^5 spp);
# one that reaches its target at once does not.
"$program" --width 256 --height 256 --target-error 0.001 --threads 1 --out "$work/long.exr" \
    >/dev/null 2>"$work/long.log" &
long_pid=$!
waited=0
while ! grep -q "will take" "$work/long.log" && kill -0 $long_pid 2>/dev/null && [ $waited -lt 200 ]; do
    sleep 0.05
    waited=$((waited + 1))
done
kill $long_pid 2>/dev/null
wait $long_pid 2>/dev/null
check "a progressive render of hours is announced ($(head -c 300 "$work/long.log"))" \
    grep -q "warning: this render will take about [0-9]* minutes" "$work/long.log"
"$program" --width 128 --height 128 --target-error 0.5 --threads 1 --out "$work/short.exr" >/dev/null 2>"$work/short.log"
check "a short progressive render is not" not_grep "will take about" "$work/short.log"

echo "resume: $checks checks, $failures failed"
[ $failures = 0 ]
