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
# and, for the programs that read them, broken OBJ, MTL and scene files and
# data directories; inputs that are not regular files or are over their
# size limit, files of another kind (whose content must not be printed),
# emitting shapes without area, and --out or its sidecars naming an input
# (status 2, the input untouched). Prints one line per failing case and a
# summary.
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
# the case put there) are allowed to remain. Set by a case after fresh_dir:
# $want, the exact exit status; $forbid, text the message must not contain
# (an input's content); $unchanged, files (in $dir) that must keep their bytes.
expect_failure() {
    local name=$1 expect=$2
    shift 3
    cases=$((cases + 1))
    local f
    for f in $unchanged; do cp "$dir/$f" "$work/saved.$f"; done
    "$@" > "$dir/.stdout" 2> "$dir/.stderr"
    local status=$? problem=""
    if [ $status -eq 0 ]; then
        problem="exit status 0"
    elif [ $status -gt 2 ]; then
        problem="exit status $status (a crash or a signal)"
    elif [ -n "$want" ] && [ $status -ne "$want" ]; then
        problem="exit status $status, expected $want"
    elif ! grep -q -F -- "$expect" "$dir/.stderr"; then
        problem="message does not mention '$expect'"
    elif [ -n "$forbid" ] && grep -q -F -- "$forbid" "$dir/.stderr"; then
        problem="message shows the input's content '$forbid'"
    elif grep -q -E "Sanitizer|runtime error|Segmentation|Assertion" "$dir/.stderr"; then
        problem="sanitizer or assertion report"
    else
        for f in $unchanged; do
            cmp -s "$dir/$f" "$work/saved.$f" || problem="changed the input $f"
        done
    fi
    if [ -z "$problem" ]; then
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
    want=""
    forbid=""
    unchanged=""
}

# expect_success NAME -- COMMAND...: the control beside a refused case (the
# same input with the limit raised, an output that is no input) must work.
expect_success() {
    local name=$1
    shift 2
    cases=$((cases + 1))
    "$@" > "$dir/.stdout" 2> "$dir/.stderr"
    local status=$?
    if [ $status -ne 0 ]; then
        failures=$((failures + 1))
        echo "FAIL $name: exit status $status, expected 0"
        sed 's/^/    stderr: /' "$dir/.stderr" | head -3
    fi
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

tri='v 0 0 0\nv 1 0 0\nv 0 1 0\n' # three vertices (printf format)
for program in "${programs[@]}"; do
    [ -x "$program" ] || { echo "FAIL $program: no such program"; failures=$((failures + 1)); continue; }
    p=$(basename "$program")
    args=$(small_args "$p")
    # shellcheck disable=SC2086
    run() { "$program" $args "$@"; }

    # ---- the shared flags ------------------------------------------------
    fresh_dir; expect_failure "$p unknown flag" "'--bogus'" -- run --out "$dir/out.exr" --bogus
    fresh_dir; expect_failure "$p stray argument" "'stray'" -- run --out "$dir/out.exr" stray
    for flag in --width --height --spp --seed --threads --exposure --out --max-input-mb; do
        fresh_dir; expect_failure "$p $flag without a value" "$flag" -- run --out "$dir/out.exr" $flag
    done
    for bad in "--width abc" "--width 0" "--width 99999999" "--width 12x" "--width 1e3" "--height -5" \
        "--height 99999999999999999999" "--spp 1.5" "--spp 0" "--seed -1" "--seed 12abc" "--threads 0" \
        "--threads nan" "--exposure nan" "--exposure inf" "--exposure -inf" "--exposure 1e999" "--exposure abc" \
        "--width=" "--spp=nan" "--max-input-mb 0" "--max-input-mb abc" "--max-input-mb 1.5" \
        "--max-input-mb 99999999" "--max-input-mb -1"; do
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
            fresh_dir
            missing=$dir/missing
            # a file the program writes (its checkpoint): what is missing is its directory
            [ "$flag" = --checkpoint ] && missing=$dir/missing/x.checkpoint
            expect_failure "$p $flag missing path" "$missing" -- run --out "$dir/out.exr" $flag "$missing" ;;
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
        "--target-error -1:09-" "--experiment-size 0:09-" "--accel octree:09-" \
        "--reference-spp 0:09-" "--experiment-spp 0:09-" "--walls maybe:13-" "--rr sometimes:13-" \
        "--bench-csv x.csv:13-" "--builtin nothing:13-" "--rr sometimes:09-"; do
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
        # A face that emits (Ke > 0) must have area, like an area light.
        fresh_dir; keep="in.obj in.mtl"; want=1
        printf 'newmtl m\nKe 1 1 1\n' > "$dir/in.mtl"
        printf 'mtllib in.mtl\nv 0 0 0\nv 1 0 0\nv 2 0 0\nusemtl m\nf 1 2 3\n' > "$dir/in.obj"
        expect_failure "$p --obj with an emitting face without area" "in.obj:6: the face emits light (material 'm', Ke > 0) but has no area" -- \
            run --out "$dir/out.exr" --obj "$dir/in.obj"

        # ---- what an input may not be -------------------------------------------
        # Not a regular file: refused before reading (/dev/zero never ends,
        # a FIFO without a writer would block: the timeout catches a hang).
        fresh_dir; want=1
        expect_failure "$p --obj /dev/zero" "/dev/zero: not a regular file (a character device)" -- run --out "$dir/out.exr" --obj /dev/zero
        fresh_dir; mkdir "$dir/in.obj"; keep="in.obj"; want=1
        expect_failure "$p --obj a directory" "in.obj: not a regular file (a directory)" -- run --out "$dir/out.exr" --obj "$dir/in.obj"
        fresh_dir; mkfifo "$dir/in.obj"; keep="in.obj"; want=1
        expect_failure "$p --obj a FIFO" "in.obj: not a regular file (a pipe)" -- timeout 60 "$program" $args --out "$dir/out.exr" --obj "$dir/in.obj"
        # Over the limit: a sparse 2 GB file (no disk, and never read), and a
        # real 2 MB file under --max-input-mb 1; with 3 it renders.
        fresh_dir; truncate -s 2G "$dir/in.obj"; keep="in.obj"; want=1
        expect_failure "$p --obj of 2 GB" "in.obj: 2.0 GB is over the 1 GB limit for OBJ files (--max-input-mb N raises it)" -- \
            run --out "$dir/out.exr" --obj "$dir/in.obj"
        fresh_dir; keep="in.obj"; want=1
        { printf "$tri"'f 1 2 3\n'; head -c 2097152 /dev/zero | tr '\0' '#'; echo; } > "$dir/in.obj"
        expect_failure "$p --obj of 2 MB, --max-input-mb 1" "in.obj: 2.0 MB is over the 1 MB limit for OBJ files (--max-input-mb N raises it)" -- \
            run --out "$dir/out.exr" --obj "$dir/in.obj" --max-input-mb 1
        expect_success "$p --obj of 2 MB, --max-input-mb 3" -- run --out "$dir/out.exr" --obj "$dir/in.obj" --max-input-mb 3
        fresh_dir; keep="in.obj"; want=1
        printf 'mtllib /dev/zero\n'"$tri"'f 1 2 3\n' > "$dir/in.obj"
        expect_failure "$p --obj with MTL /dev/zero" "in.obj:1: cannot read material library '/dev/zero': not a regular file" -- \
            run --out "$dir/out.exr" --obj "$dir/in.obj"
        fresh_dir; keep="in.obj in.mtl"; want=1
        printf 'mtllib in.mtl\n'"$tri"'f 1 2 3\n' > "$dir/in.obj"
        { echo "newmtl m"; head -c 2097152 /dev/zero | tr '\0' '#'; echo; } > "$dir/in.mtl"
        expect_failure "$p --obj with an MTL of 2 MB, --max-input-mb 1" "in.mtl': 2.0 MB is over the 1 MB limit for MTL files (--max-input-mb N raises it)" -- \
            run --out "$dir/out.exr" --obj "$dir/in.obj" --max-input-mb 1
        # A file of another kind: named with its line, its content not shown
        # (an OBJ, or an mtllib, could name a private key).
        fresh_dir; keep="in.obj"; want=1; forbid="SECRET"
        printf 'SECRET-TOKEN-7f3a and more\n' > "$dir/in.obj"
        expect_failure "$p --obj of another kind" "in.obj:1: not an OBJ file" -- run --out "$dir/out.exr" --obj "$dir/in.obj"
        fresh_dir; keep="in.obj key.txt"; want=1; forbid="SECRET"
        printf '# key\nSECRET-TOKEN-7f3a and more\n' > "$dir/key.txt"
        printf 'mtllib key.txt\n'"$tri"'f 1 2 3\n' > "$dir/in.obj"
        expect_failure "$p --obj with an MTL of another kind" "key.txt:2: not an MTL file" -- run --out "$dir/out.exr" --obj "$dir/in.obj"

        # ---- --out and its sidecars may not name an input (status 2, input kept) --
        out_case() { # NAME OBJ_NAME OUT_NAME [OBJ_ARG]: the OBJ is written as $dir/OBJ_NAME, named $dir/OBJ_ARG
            fresh_dir; printf "${tri}f 1 2 3\n" > "$dir/$2"; keep="$2"; unchanged="$2"; want=2
            expect_failure "$p $1" "--out '$dir/$3' would overwrite the input '$dir/${4:-$2}'" -- \
                run --out "$dir/$3" --obj "$dir/${4:-$2}"
        }
        out_case "--out is the --obj file" in.png in.png
        out_case "--out is the --obj file as ./" in.png in.png ./in.png
        out_case "--out's .png preview is the --obj file" out.png out.exr
        out_case "--out's counters file is the --obj file" out.counters.json out.exr
        fresh_dir; printf "${tri}f 1 2 3\n" > "$dir/in.obj"; ln "$dir/in.obj" "$dir/out.png"
        keep="in.obj out.png"; unchanged="in.obj"; want=2
        expect_failure "$p --out is a hard link to the --obj file" "--out '$dir/out.png' would overwrite the input '$dir/in.obj'" -- \
            run --out "$dir/out.png" --obj "$dir/in.obj"
        fresh_dir; keep="in.obj out.png"; unchanged="out.png"; want=2
        printf 'mtllib out.png\n'"$tri"'usemtl m\nf 1 2 3\n' > "$dir/in.obj"; printf 'newmtl m\nKd 1 1 1\n' > "$dir/out.png"
        expect_failure "$p --out's preview is the MTL file" "--out '$dir/out.exr' would overwrite the input '$dir/out.png' (its .png preview)" -- \
            run --out "$dir/out.exr" --obj "$dir/in.obj"
        # The control: an old output that is no input is replaced as usual.
        fresh_dir; printf "${tri}f 1 2 3\n" > "$dir/in.obj"; echo old > "$dir/out.png"
        expect_success "$p --out replaces an old output" -- run --out "$dir/out.png" --obj "$dir/in.obj"
        cmp -s "$dir/out.png" - <<< old && { failures=$((failures + 1)); echo "FAIL $p --out replaces an old output: it did not"; }
    fi

    # ---- scene files (every program but 08, which has no scene) -----------------
    case $p in 08-*) ;; *)
        scene_case() { # NAME TEXT EXPECTED: the text is written to $dir/in.scene; status 1
            fresh_dir; printf "$2" > "$dir/in.scene"; keep="in.scene"; want=1
            expect_failure "$p --scene $1" "$3" -- run --out "$dir/out.exr" --scene "$dir/in.scene"
        }
        cam='camera eye 0 0 5 target 0 0 0 up 0 1 0 fov 40\n'
        glow='material glow emissive emission 4 4 4\n'
        scene_case "an emitting quad without area" "$cam${glow}quad p0 0 0 0 p1 1 0 0 p2 2 0 0 p3 0 1 0 material glow\n" \
            "in.scene:3:1: the quad emits light (material 'glow') but has no area"
        scene_case "an emitting triangle without area" "$cam${glow}triangle p0 0 0 0 p1 0 0 0 p2 1 1 1 material glow\n" \
            "in.scene:3:1: the triangle emits light (material 'glow') but has no area"
        scene_case "an area light without area" "${cam}light area p0 0 0 0 p1 1 0 0 p2 2 0 0 p3 0 1 0 emission 4 4 4\n" \
            "in.scene:2:7: the area light has no area"
        fresh_dir; printf 'SECRET-TOKEN-7f3a and more\n' > "$dir/in.scene"; keep="in.scene"; want=1; forbid="SECRET"
        expect_failure "$p --scene of another kind" "in.scene:1:1: not a scene file" -- run --out "$dir/out.exr" --scene "$dir/in.scene"
        # Chapter 07 takes only the camera and the lights from a scene.
        case $p in 07-*) ;; *)
            scene_case "naming a mesh that is /dev/zero" "${cam}mesh path \"/dev/zero\"\n" \
                "in.scene:2:1: mesh: /dev/zero: not a regular file" ;;
        esac
        fresh_dir; want=1
        expect_failure "$p --scene /dev/zero" "/dev/zero: not a regular file (a character device)" -- run --out "$dir/out.exr" --scene /dev/zero
        fresh_dir; truncate -s 17M "$dir/in.scene"; keep="in.scene"; want=1
        expect_failure "$p --scene of 17 MB" "in.scene: 17.0 MB is over the 16 MB limit for scene files" -- \
            run --out "$dir/out.exr" --scene "$dir/in.scene"
        fresh_dir; printf "$cam" > "$dir/in.png"; keep="in.png"; unchanged="in.png"; want=2
        expect_failure "$p --out is the --scene file" "--out '$dir/in.png' would overwrite the input '$dir/in.png'" -- \
            run --out "$dir/in.png" --scene "$dir/in.png"
        fresh_dir; printf "${cam}mesh path \"out.png\"\n" > "$dir/in.scene"; printf "${tri}f 1 2 3\n" > "$dir/out.png"
        keep="in.scene out.png"; unchanged="out.png"; want=2
        expect_failure "$p --out's preview is a mesh of the scene" "--out '$dir/out.exr' would overwrite the input '$dir/out.png' (its .png preview)" -- \
            run --out "$dir/out.exr" --scene "$dir/in.scene"
        ;;
    esac
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

# ---- a camera that sees nothing lit ---------------------------------------
# Below the Cornell box and looking away from it, the camera sees only the
# black sky: the render must say so (a camera placed in another program's
# coordinates does exactly this), and the same render seen right must not.
for p in 09-path-tracing 13-production; do
    program=$bin/$p
    case " ${programs[*]} " in *" $program "*) ;; *) continue ;; esac
    fresh_dir
    cases=$((cases + 2))
    if ! "$program" --width 16 --height 12 --spp 2 --threads 1 --eye 278,-200,-300 --target 278,-200,0 \
        --out "$dir/out.exr" > /dev/null 2> "$dir/.stderr" || ! grep -q "every pixel of the image is black" "$dir/.stderr"; then
        failures=$((failures + 1))
        echo "FAIL $p: a camera that sees only the black sky gives no warning"
    fi
    "$program" --width 16 --height 12 --spp 2 --threads 1 --out "$dir/out.exr" > /dev/null 2> "$dir/.stderr"
    if grep -q "every pixel of the image is black" "$dir/.stderr"; then
        failures=$((failures + 1))
        echo "FAIL $p: the Cornell box seen right is called black"
    fi
done

echo "bad input: $cases cases, $failures failed"
[ $failures -eq 0 ]
