#!/bin/bash
# long_render.sh -- every program that renders a picture warns before a
# render that will take far more than a minute, and an interrupted render
# leaves nothing behind.
#
#   tests/long_render.sh BUILD_DIR   (run by `make test`)
#
# Each program is asked for a 2048x2048 image at 1024 samples per pixel on
# one thread: hours for any of them. The pilot (64 pixels at the full spp,
# common/program/program.c) costs 1/65536 of that, so the warning must reach stderr
# within seconds, before the render proper; the program is then stopped with
# SIGTERM and must have written no image, preview or counters file.
# Each entry is the program and the flags that pick its own render loop:
# chapter 11's bidirectional loop and chapter 12's Metropolis chains are
# not program_render()'s, nor is chapter 13's eight-paths-at-a-time renderer.
set -u
build=${1:?usage: long_render.sh BUILD_DIR}
bin=$build/bin
work=$(mktemp -d "${TMPDIR:-/tmp}/long_render.XXXXXX")
pid=
trap '[ -n "$pid" ] && kill -9 "$pid" 2>/dev/null; rm -rf "$work"' EXIT
failures=0
cases=0
renders=(
    "01-ray-casting"
    "02-whitted"
    "06-bvh"
    "09-path-tracing"
    "10-distribution"
    "11-bidirectional"
    "11-bidirectional --integrator pt"
    "12-metropolis"
    "12-metropolis --path-trace"
    "13-production"
    "13-production --one-path"
)

for entry in "${renders[@]}"; do
    read -r program flags <<< "$entry"
    [ -x "$bin/$program" ] || continue
    cases=$((cases + 1))
    dir=$work/$cases
    mkdir -p "$dir"
    # shellcheck disable=SC2086
    "$bin/$program" $flags --width 2048 --height 2048 --spp 1024 --threads 1 --out "$dir/out.exr" \
        > "$dir/stdout" 2> "$dir/stderr" &
    pid=$!
    warned=no
    for _ in $(seq 1 600); do # up to 60 s on a loaded machine
        if grep -qs "warning: this render will take about" "$dir/stderr"; then warned=yes; break; fi
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.1
    done
    kill -TERM "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
    pid=
    left=$(cd "$dir" && ls -A | grep -v -x -e stdout -e stderr)
    if [ $warned = no ]; then
        failures=$((failures + 1))
        echo "FAIL: $entry: no warning before a render of hours; stderr was:"
        sed 's/^/    /' "$dir/stderr" | head -5
    elif [ -n "$left" ]; then
        failures=$((failures + 1))
        echo "FAIL: $entry: stopped mid-render, left $(echo $left)"
    else
        echo "ok: $entry: $(grep -o 'about [0-9]* [a-z]*' "$dir/stderr" | head -1) -- warned, stopped, nothing written"
    fi
done
echo "long renders: $cases cases, $failures failed"
[ $failures -eq 0 ]
