#!/bin/bash
# bad_input.sh -- every chapter program, fed bad input, must fail cleanly.
#
#   tests/bad_input.sh BUILD_DIR [PROGRAM...]   (run by `make test`, one program at a time)
#
# For every program in BUILD_DIR/bin (or the PROGRAMs named, such as
# 01-ray-casting) and every case below the run must:
#   - exit with status 1 or 2 (not 0, and not killed by a signal: no crash);
#   - print a message on stderr that names the flag, or the file and line;
#   - leave no output file (image, preview, CSV) and no temporary file behind.
# Cases: unknown flags, missing values, non-numbers, out-of-range values,
# NaN and Inf, unwritable or impossible outputs, a full disk (simulated with
# a file-size limit: write() then fails with EFBIG, as it would with ENOSPC),
# and, for the programs that read them, broken OBJ and MTL files and data
# directories. Prints one line per failing case and a summary.
set -u
build=${1:?usage: bad_input.sh BUILD_DIR [PROGRAM...]}
bin=$build/bin
shift
if [ $# -gt 0 ]; then programs=("${@/#/$bin/}"); else programs=("$bin"/[0-9][0-9]-*); fi
work=$(mktemp -d "${TMPDIR:-/tmp}/bad_input.XXXXXX")
trap 'chmod -R u+w "$work" 2>/dev/null; rm -rf "$work"' EXIT
cases=0
failures=0

# Small, quick arguments for each program, so the cases that get as far as
# rendering (a full disk) take a fraction of a second.
small_args() {
    case $1 in
    04-*) echo "--width 16 --height 12 --threads 1 --quiet --triangles 1024 --probe-rays 0" ;;
    05-* | 06-*) echo "--width 16 --height 12 --threads 1 --quiet --triangles 1024" ;;
    07-*) echo "--width 16 --height 12 --threads 1 --quiet --bounces 2" ;;
    08-*) echo "--width 16 --height 12 --threads 1 --quiet --quick" ;;
    09-*) echo "--width 16 --height 12 --threads 1 --quiet --spp 1" ;;
    *) echo "--width 16 --height 12 --threads 1 --quiet" ;;
    esac
}

# expect_failure NAME EXPECTED_TEXT -- COMMAND...
# Runs COMMAND in a fresh directory $dir (its outputs go to $dir/out.*),
# then checks status, message and leftovers. Files listed in $keep (inputs
# the case put there) are allowed to remain.
expect_failure() {
    local name=$1 expect=$2
    shift 3
    cases=$((cases + 1))
    "$@" > "$dir/.stdout" 2> "$dir/.stderr"
    local status=$? problem=""
    if [ $status -eq 0 ]; then
        problem="exit status 0"
    elif [ $status -gt 2 ]; then
        problem="exit status $status (a crash or a signal)"
    elif ! grep -q -F -- "$expect" "$dir/.stderr"; then
        problem="message does not mention '$expect'"
    elif grep -q -E "Sanitizer|runtime error|Segmentation|Assertion" "$dir/.stderr"; then
        problem="sanitizer or assertion report"
    else
        local left
        left=$(cd "$dir" && ls -A | grep -v -x -F -e .stdout -e .stderr $(for k in $keep; do printf -- '-e %s ' "$k"; done))
        [ -n "$left" ] && problem="left files behind: $(echo $left)"
    fi
    if [ -n "$problem" ]; then
        failures=$((failures + 1))
        echo "FAIL $name: $problem"
        sed 's/^/    stderr: /' "$dir/.stderr" | head -3
    fi
}

fresh_dir() {
    dir=$work/case$cases
    rm -rf "$dir"
    mkdir -p "$dir"
    keep=""
}

# A read-only directory. root ignores permissions, so as root the program is
# run as 'nobody' (setpriv) for that case; without setpriv it is skipped.
as_unprivileged() {
    if [ "$(id -u)" = 0 ]; then
        setpriv --reuid=65534 --regid=65534 --clear-groups -- "$@"
    else
        "$@"
    fi
}
can_drop=1
if [ "$(id -u)" = 0 ] && ! command -v setpriv > /dev/null 2>&1; then can_drop=0; fi

# A full disk: ignore SIGXFSZ so that write() returns an error instead of
# the process being killed, and cap every file at KB kilobytes (0: nothing
# can be written at all). The cap applies to every regular file the process
# writes, stderr included when it is one, so the program's output goes
# through a pipe (to cat, outside the cap); pipefail keeps its status.
full_disk() { # KB COMMAND...
    local kb=$1
    shift
    (set -o pipefail; (trap '' XFSZ; ulimit -f "$kb"; exec "$@" 2>&1) | cat >&2)
}

for program in "${programs[@]}"; do
    [ -x "$program" ] || { echo "FAIL $program: no such program"; failures=$((failures + 1)); continue; }
    p=$(basename "$program")
    args=$(small_args "$p")
    # shellcheck disable=SC2086
    run() { "$program" $args "$@"; }

    # ---- the shared flags ------------------------------------------------
    fresh_dir; expect_failure "$p unknown flag" "'--bogus'" -- run --out "$dir/out.exr" --bogus
    fresh_dir; expect_failure "$p stray argument" "'stray'" -- run --out "$dir/out.exr" stray
    for flag in --width --height --spp --seed --threads --exposure --out; do
        fresh_dir; expect_failure "$p $flag without a value" "$flag" -- run --out "$dir/out.exr" $flag
    done
    for bad in "--width abc" "--width 0" "--width 99999999" "--width 12x" "--width 1e3" "--height -5" \
        "--height 99999999999999999999" "--spp 1.5" "--spp 0" "--seed -1" "--seed 12abc" "--threads 0" \
        "--threads nan" "--exposure nan" "--exposure inf" "--exposure -inf" "--exposure 1e999" "--exposure abc" \
        "--width=" "--spp=nan"; do
        flag=${bad%% *}; flag=${flag%%=*}
        fresh_dir
        if [ "${bad#*=}" != "$bad" ]; then
            expect_failure "$p $bad" "$flag" -- run --out "$dir/out.exr" "$bad"
        else
            # shellcheck disable=SC2086
            expect_failure "$p $bad" "$flag" -- run --out "$dir/out.exr" $bad
        fi
    done

    # ---- outputs that cannot be written -----------------------------------
    fresh_dir; expect_failure "$p --out into a missing directory" "--out" -- run --out "$dir/missing/out.exr"
    fresh_dir; expect_failure "$p --out with a wrong extension" "--out" -- run --out "$dir/out.txt"
    fresh_dir; expect_failure "$p --out under a file" "--out" -- run --out "/dev/null/out.exr"
    fresh_dir; mkdir "$dir/out.exr"; keep="out.exr"
    expect_failure "$p --out is a directory" "out.exr" -- run --out "$dir/out.exr"
    if [ $can_drop = 1 ]; then
        fresh_dir; mkdir "$dir/ro"; chmod 555 "$dir/ro"; chmod 777 "$dir"; keep="ro"
        expect_failure "$p --out into a read-only directory" "--out" -- as_unprivileged "$program" $args --out "$dir/ro/out.exr"
    fi
    # Nothing writable: the first write fails (inside the EXR header).
    fresh_dir; expect_failure "$p full disk (.exr)" "out.exr" -- full_disk 0 "$program" $args --out "$dir/out.exr"
    fresh_dir; expect_failure "$p full disk (.png)" "out.png" -- full_disk 0 "$program" $args --out "$dir/out.png"
    # Full part way through: 4 KB, less than a 256 x 192 EXR (590 KB
    # uncompressed) and, for every chapter's picture, its PNG.
    fresh_dir; expect_failure "$p disk full mid-file (.exr)" "out.exr" -- full_disk 4 "$program" $args --width 256 --height 192 --out "$dir/out.exr"
    fresh_dir; expect_failure "$p disk full mid-file (.png)" "out.png" -- full_disk 4 "$program" $args --width 256 --height 192 --out "$dir/out.png"

    # ---- the chapter's own flags (from its --help) --------------------------
    help=$("$program" --help)
    extras=$(echo "$help" | sed -n '/^flags of /,$p' | sed -n 's/^  \(--[a-z0-9-]*\) \([^ ]*\).*/\1 \2/p')
    while read -r flag metavar; do
        [ -n "$flag" ] || continue
        case $metavar in
        FILE | DIR)
            fresh_dir; expect_failure "$p $flag missing path" "$dir/missing" -- run --out "$dir/out.exr" $flag "$dir/missing" ;;
        [A-Z]* | *"|"*)
            fresh_dir; expect_failure "$p $flag without a value" "$flag" -- run --out "$dir/out.exr" $flag
            for bad in abc nan inf -inf "" 1e999; do
                fresh_dir; expect_failure "$p $flag '$bad'" "$flag" -- run --out "$dir/out.exr" $flag "$bad"
            done ;;
        esac
    done <<< "$extras"

    # ---- out-of-range values of the chapters' own flags ----------------------
    for bad in "--max-depth 65:02-" "--max-depth -1:02-" "--triangles 0:04-" "--triangles 0:05-" "--triangles -1:06-" \
        "--density 0:04-" "--density -1:04-" "--heatmap-max 0:04-" "--heatmap-max -1:05-" "--traversal-cost -1:05-" \
        "--intersection-cost 0:05-" "--empty-bonus -1:05-" "--empty-bonus 2:05-" "--max-depth -1:05-" \
        "--max-depth 100000:05-" "--heatmap-max -1:06-" "--rho 1:07-" "--rho -0.1:07-" "--bounces 0:07-" \
        "--bounces 1001:07-" "--runs 0:08-" "--runs 1:08-" "--max-log2n -1:08-" "--max-log2n 99:08-" \
        "--rr-probability 0:09-" "--rr-probability 1.5:09-" "--max-depth -1:09-" "--time-budget -1:09-" \
        "--target-error -1:09-" "--experiment-size 0:09-" "--walls maybe:09-" \
        "--reference-spp 0:09-" "--experiment-spp 0:09-" "--wide --time-budget 1:09-" \
        "--wide --builtin veach:09-" "--wide --integrator mis:09-" "--wide --explain 1,1:09-"; do
        only=${bad##*:}; bad=${bad%:*}
        case $p in "$only"*) ;; *) continue ;; esac
        flag=${bad%% *}
        # shellcheck disable=SC2086
        fresh_dir; expect_failure "$p $bad" "$flag" -- run --out "$dir/out.exr" $bad
    done

    # ---- files the chapter reads ----------------------------------------------
    if echo "$help" | grep -q -- "--obj FILE"; then
        obj_case() { # NAME TEXT EXPECTED (the text is written to $dir/in.obj)
            fresh_dir; printf "$2" > "$dir/in.obj"; keep="in.obj"
            [ -n "${3:-}" ] && expect=$3 || expect="in.obj:"
            expect_failure "$p --obj $1" "$expect" -- run --out "$dir/out.exr" --obj "$dir/in.obj"
        }
        tri='v 0 0 0\nv 1 0 0\nv 0 1 0\n'
        obj_case "empty file" "" "in.obj"
        obj_case "comments only" "# nothing here\n\n" "in.obj"
        obj_case "NaN coordinate" 'v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n' "in.obj:2"
        obj_case "Inf coordinate" 'v 0 0 0\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n' "in.obj:3"
        obj_case "huge coordinate" 'v 0 0 1e39\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' "in.obj:1"
        obj_case "index out of range" "${tri}f 1 2 4\n" "in.obj:4"
        obj_case "huge index" "${tri}f 1 2 99999999999999999999\n" "in.obj:4"
        obj_case "index zero" "${tri}f 0 1 2\n" "in.obj:4"
        obj_case "negative index too far back" "${tri}f -1 -2 -4\n" "in.obj:4"
        obj_case "truncated face" "${tri}f 1 2\n" "in.obj:4"
        obj_case "truncated vertex" 'v 0 0 0\nv 1 0\n' "in.obj:2"
        obj_case "truncated face vertex" "${tri}f 1/ 2 3/\n" "in.obj:4"
        obj_case "not a number" "${tri}v 1 x 0\n" "in.obj:4"
        obj_case "binary garbage" '\x7fELF\x02\x01\x01\x00\xff\xfe\x00\x01\n\x89PNG\n' "in.obj:1"
        obj_case "missing mtl file" "mtllib nowhere.mtl\n${tri}f 1 2 3\n" "nowhere.mtl"
        obj_case "unknown material" "${tri}usemtl nothing\nf 1 2 3\n" "in.obj:4"
        mtl_case() { # NAME MTL_TEXT EXPECTED
            fresh_dir; printf "$2" > "$dir/in.mtl"; keep="in.obj in.mtl"
            printf 'mtllib in.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n' > "$dir/in.obj"
            expect_failure "$p --obj with MTL $1" "$3" -- run --out "$dir/out.exr" --obj "$dir/in.obj"
        }
        mtl_case "bad Kd" 'newmtl m\nKd 0.5 x 0.5\n' "in.mtl:2"
        mtl_case "NaN Kd" 'newmtl m\nKd 0.5 nan 0.5\n' "in.mtl:2"
        mtl_case "Inf Ke" 'newmtl m\nKe inf 0 0\n' "in.mtl:2"
        mtl_case "two of three Kd values" 'newmtl m\nKd 0.5 0.5\n' "in.mtl:2"
        mtl_case "statement before newmtl" 'Kd 0.5 0.5 0.5\nnewmtl m\n' "in.mtl:1"
        mtl_case "garbage" 'newmtl m\n\x01\x02\x03\xff\n' "in.mtl:2"
        mtl_case "empty (material never defined)" '' "in.obj"
    fi
    if echo "$help" | grep -q -- "--data DIR"; then
        fresh_dir; touch "$dir/file"; keep="file"
        expect_failure "$p --data is a file" "$dir/file" -- run --out "$dir/out.exr" --data "$dir/file"
        fresh_dir; mkdir "$dir/data"; keep="data"
        case $p in
        09-*) data_args="--experiment-size 8 --reference-spp 16 --experiment-spp 2" ;;
        11-*) data_args="--experiment-size 8 --reference-spp 16 --experiment-seconds 0.1" ;;
        *) data_args="" ;;
        esac
        # Nothing can be written: whichever file comes first (image or table)
        # must fail, and nothing may be left in either directory.
        expect_failure "$p --data on a full disk" "$dir/" -- full_disk 0 "$program" $args $data_args --out "$dir/out.exr" --data "$dir/data"
        left=$(ls -A "$dir/data" 2> /dev/null)
        if [ -n "$left" ]; then
            failures=$((failures + 1)); echo "FAIL $p --data on a full disk: left $(echo $left) in the data directory"
        fi
    fi
done

echo "bad input: $cases cases, $failures failed"
[ $failures -eq 0 ]
