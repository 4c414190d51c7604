#!/bin/sh
# bench.sh BUILD [quick|full] [all|cycles] -- make bench: every table in one run.
#
#   1. the acceleration structures against Embree's (the harness
#      ../shared/anchors/embree_bench.c), size by size, Embree then ours,
#      twice over (A B A B), each ours-table with the ratios to the Embree
#      run just before it
#   2. chapter 13's table of what each step buys, on the Cornell box, and
#      the same renderer on Embree's kernels (bench_pt_embree)
#   3. the benchmark scenes (bench_scenes --speed): chapter 13's renderer,
#      the same on Embree's kernels, chapter 09's MIS rung; s/M wall and
#      CPU, Mrays/s, 1 and 2 threads, cases taking turns, best of N
#   4. Cycles at equal CPU time (tests/bench_cycles.py, bench_equal_time),
#      where blender is installed: ours, Cycles, MIS at each spp in turn
#   5. many lights: chapter 13 with its light tree against the same
#      renderer picking lights by power (chapter 09's pick), at equal CPU
#      time on the many-lights box (bench_equal_time, anchored on power)
#
# quick (the default): small images, few repeats, the 1M-triangle mesh in
# the speed table only: a few minutes on 2 cores. full (make bench
# FULL=1): every size, larger images, more repeats, every scene in the
# Cycles comparison: about an hour on 2 cores. `cycles` runs part 4
# alone (make bench-cycles); SCENES="A B" in the environment (make bench
# SCENES=...) limits part 4 to those scenes. Everything lands in
# BUILD/bench/ and BUILD/data/.
set -u
# OpenMP's idle threads sleep instead of spinning. A program that runs on 2
# threads and then on 1 keeps its second thread; spinning, it is charged to
# the process while the other works, and the 1-thread CPU times came out up
# to 40 % above the wall times, more for the faster renderer.
export OMP_WAIT_POLICY=passive
BUILD=${1:?usage: bench.sh BUILD [quick|full] [all|cycles]}
MODE=${2:-quick}
PARTS=${3:-all}
BIN=$BUILD/bin
OUT=$BUILD/bench
DATA=$BUILD/data
mkdir -p "$OUT/scenes" "$OUT/runs" "$OUT/ref" "$DATA" "$BUILD/out"

if [ "$MODE" = full ]; then
    ACCEL_SIZES="1024 10240 102400 1048576" ACCEL_ARGS="--reps 3"
    TABLE_ARGS="--width 256 --spp 16" EMBREE_PT_ARGS="--width 256 --spp 16 --reps 5"
    SPEED_ARGS="--width 256 --spp 16 --reps 5"
    CYCLES_SCENES="cornell cornell-10k cornell-100k cornell-1m glossy-glass open-100k many-lights"
    CYCLES_WIDTH=128 REFERENCE_SPP=8192 CYCLES_SPP="16 64 256" OURS_EXTRA_SPP="1024" SEEDS="1 2"
    LIGHTS_WIDTH=128 LIGHTS_REFERENCE_SPP=8192 LIGHTS_SPP="64 256 1024"
else
    ACCEL_SIZES="10240 102400" ACCEL_ARGS="--reps 1 --only wide-bvh-sah,wide-bvh-quantized,wide-bvh-stream"
    TABLE_ARGS="--width 96 --spp 8" EMBREE_PT_ARGS="--width 64 --spp 8 --reps 3"
    SPEED_ARGS="--width 96 --spp 8 --reps 3"
    CYCLES_SCENES="cornell-10k glossy-glass open-100k"
    CYCLES_WIDTH=64 REFERENCE_SPP=1024 CYCLES_SPP="16 64" OURS_EXTRA_SPP="256" SEEDS="1"
    LIGHTS_WIDTH=64 LIGHTS_REFERENCE_SPP=2048 LIGHTS_SPP="64 256"
fi

CYCLES_SCENES=${SCENES:-$CYCLES_SCENES}
ALL_SCENES="cornell cornell-10k cornell-100k cornell-1m glossy-glass open-100k many-lights"
for s in $CYCLES_SCENES; do
    case " $ALL_SCENES " in
    *" $s "*) ;;
    *) echo "bench.sh: SCENES names '$s', not a benchmark scene (the scenes: $ALL_SCENES)" >&2; exit 2 ;;
    esac
done

echo "== make bench ($MODE): $(nproc) processors, load average $(cut -d' ' -f1-3 /proc/loadavg)"
START=$(date +%s)

# The scene set, written once (the 1M mesh takes a few seconds).
for s in $ALL_SCENES; do
    [ -f "$OUT/scenes/$s.scene" ] && [ "$OUT/scenes/$s.scene" -nt "$BIN/bench_scenes" ] ||
        "$BIN/bench_scenes" --write "$OUT/scenes" --scenes "$s" || exit 1
done

if [ "$PARTS" = all ]; then
    echo
    echo "== 1. acceleration structures against Embree (rtcIntersect1), size by size, A B A B"
    echo "   (builds on $(nproc) threads each, Embree's at its default quality; rays on one thread each)"
    if [ -x "$BIN/embree_bench" ]; then
        for n in $ACCEL_SIZES; do
            for rep in 1 2; do
                "$BIN/embree_bench" embree "$n" medium "$(nproc)" 3 | tee "$OUT/embree-$n-$rep.txt"
                stadium=""
                [ "$MODE" = full ] && [ "$rep" = 2 ] && [ "$n" = 1024 ] && stadium="--stadium $DATA/stadium.csv"
                # shellcheck disable=SC2086
                "$BIN/bench_accel" --sizes "$n" $ACCEL_ARGS --embree "$OUT/embree-$n-$rep.txt" \
                    --out "$OUT/accel-$n-$rep.csv" $stadium || exit 1
            done
        done
        if [ "$MODE" = full ]; then # the second pass's figures, for make plots
            first=1
            for n in $ACCEL_SIZES; do
                if [ $first = 1 ]; then cat "$OUT/accel-$n-2.csv"; first=0; else tail -n +2 "$OUT/accel-$n-2.csv"; fi
            done > "$DATA/accel.csv.tmp" && mv "$DATA/accel.csv.tmp" "$DATA/accel.csv"
            printf 'full\t%s\n' "make bench FULL=1 (build/bin/bench_accel --sizes N $ACCEL_ARGS, after Embree's run)" \
                > "$DATA/accel.run"
        fi
    else
        echo "no Embree harness (../shared/anchors/embree_bench.c, or SHARED=DIR): structures timed without it"
        # shellcheck disable=SC2086
        "$BIN/bench_accel" --sizes "$(echo $ACCEL_SIZES | tr ' ' ,)" $ACCEL_ARGS || exit 1
    fi

    echo
    echo "== 2. chapter 13's steps on the Cornell box, and on Embree's kernels"
    # shellcheck disable=SC2086
    "$BIN/13-production" --bench $TABLE_ARGS --bench-csv "$DATA/ch13_speed.csv" || exit 1
    if [ -x "$BIN/bench_pt_embree" ]; then
        # shellcheck disable=SC2086
        "$BIN/bench_pt_embree" $EMBREE_PT_ARGS --data "$DATA" || exit 1
    else
        echo "no Embree header (make bench-deps): the path tracer on Embree skipped"
    fi

    echo
    echo "== 3. the benchmark scenes: chapter 13, the same on Embree, chapter 09's MIS rung"
    # shellcheck disable=SC2086
    "$BIN/bench_scenes" --speed "$OUT/scenes" $SPEED_ARGS --csv "$DATA/bench_scenes.csv" || exit 1
fi

echo
echo "== 4. Cycles at equal CPU time ($CYCLES_WIDTH x $CYCLES_WIDTH, 2 threads; reference: chapter 09 mis, $REFERENCE_SPP spp)"
if ! command -v blender > /dev/null 2>&1; then
    echo "no blender: the Cycles comparison skipped (make bench-cycles installs Debian's blender and runs it)"
else
    blender --version 2> /dev/null | head -1
    MANIFEST=$OUT/runs-$MODE.csv
    # bench_scenes' arguments for a manifest row's renderer: ch13-lecture
    # is chapter 13's renderer on the lecture rung (--integrator lecture)
    ours_args() {
        case $2 in
        "$1"-lecture | "$1"-cosine | "$1"-mis) OURS="--renderer $1 --integrator ${2#"$1"-}" ;;
        *) OURS="--renderer $2" ;;
        esac
    }
    : > "$MANIFEST"
    for s in $CYCLES_SCENES; do
        scene=$OUT/scenes/$s.scene
        ref=$OUT/ref/$s-$CYCLES_WIDTH-$REFERENCE_SPP.exr
        [ -f "$ref" ] || "$BIN/bench_scenes" --reference "$scene" --spp "$REFERENCE_SPP" --width "$CYCLES_WIDTH" \
            --threads 2 --out "$ref" || exit 1
        ln -sf "$(basename "$ref")" "$OUT/ref/$s.exr"
        ln -sf "$(basename "$ref" .exr)-stderr.exr" "$OUT/ref/$s-stderr.exr"
        # ours (its program's MIS rung, and the lecture rung eight paths at a
        # time), Cycles, chapter 09's MIS, in turn at each sample count and
        # seed (A B C D A B C D ...)
        for spp in $CYCLES_SPP; do
            for seed in $SEEDS; do
                for r in ch13 ch13-lecture cycles ch09-mis; do
                    img=$OUT/runs/$s-$r-$spp-$seed.exr
                    if [ $r = cycles ]; then
                        blender -b --factory-startup -P tests/bench_cycles.py -- --scene "$scene" --spp "$spp" \
                            --width "$CYCLES_WIDTH" --threads 2 --seed "$seed" --out "$img" --manifest "$MANIFEST" \
                            2>&1 | grep '^bench_cycles.py' || { echo "blender failed on $s"; exit 1; }
                    else
                        ours_args ch13 $r
                        # shellcheck disable=SC2086
                        "$BIN/bench_scenes" --render "$scene" $OURS --spp "$spp" --width "$CYCLES_WIDTH" \
                            --threads 2 --seed "$seed" --out "$img" --manifest "$MANIFEST" || exit 1
                    fi
                done
            done
        done
        # ours is faster per sample: more samples, so that its curve reaches Cycles' CPU times
        for spp in $OURS_EXTRA_SPP; do
            for seed in $SEEDS; do
                for r in ch13 ch13-lecture; do
                    ours_args ch13 $r
                    # shellcheck disable=SC2086
                    "$BIN/bench_scenes" --render "$scene" $OURS --spp "$spp" --width "$CYCLES_WIDTH" \
                        --threads 2 --seed "$seed" --out "$OUT/runs/$s-$r-$spp-$seed.exr" --manifest "$MANIFEST" ||
                        exit 1
                done
            done
        done
    done
    "$BIN/bench_equal_time" --manifest "$MANIFEST" --references "$OUT/ref" --csv "$DATA/bench_equal_time.csv" || exit 1
    case " $CYCLES_SCENES " in
    *" many-lights "*)
        blender --version 2> /dev/null | head -1 | grep -q '^Blender 3\.[0-4]\.' &&
            echo "many-lights: this Blender's Cycles has no light tree (Cycles has one from Blender 3.5 on)" ;;
    esac
fi

if [ "$PARTS" = all ]; then
    echo
    echo "== 5. many lights: chapter 13's light tree against its pick by power, equal CPU time ($LIGHTS_WIDTH x $LIGHTS_WIDTH, 2 threads; reference: chapter 09 mis, $LIGHTS_REFERENCE_SPP spp)"
    # Its own reference directory: bench_equal_time reads REFDIR/SCENE.exr,
    # and part 4 may render the same scene at another size.
    mkdir -p "$OUT/ref-lights"
    scene=$OUT/scenes/many-lights.scene
    ref=$OUT/ref-lights/many-lights-$LIGHTS_WIDTH-$LIGHTS_REFERENCE_SPP.exr
    # part 4's, where it rendered the same one (FULL=1: a few CPU minutes saved)
    same=$OUT/ref/many-lights-$LIGHTS_WIDTH-$LIGHTS_REFERENCE_SPP.exr
    if [ ! -f "$ref" ] && [ -f "$same" ] && [ -f "${same%.exr}-stderr.exr" ]; then
        cp "$same" "$ref" && cp "${same%.exr}-stderr.exr" "${ref%.exr}-stderr.exr"
    fi
    [ -f "$ref" ] || "$BIN/bench_scenes" --reference "$scene" --spp "$LIGHTS_REFERENCE_SPP" --width "$LIGHTS_WIDTH" \
        --threads 2 --out "$ref" || exit 1
    ln -sf "$(basename "$ref")" "$OUT/ref-lights/many-lights.exr"
    ln -sf "$(basename "$ref" .exr)-stderr.exr" "$OUT/ref-lights/many-lights-stderr.exr"
    MANIFEST=$OUT/runs-lights-$MODE.csv
    : > "$MANIFEST"
    # Tree and power in turn at each spp and seed. From 64 spp: below, the
    # tree's build (a few hundredths of a second) is much of a 64 x 64 render.
    for spp in $LIGHTS_SPP; do
        for seed in $SEEDS; do
            for lights in tree power; do
                "$BIN/bench_scenes" --render "$scene" --lights $lights --spp "$spp" --width "$LIGHTS_WIDTH" \
                    --threads 2 --seed "$seed" --out "$OUT/runs/many-lights-$lights-$spp-$seed.exr" \
                    --manifest "$MANIFEST" || exit 1
            done
        done
    done
    "$BIN/bench_equal_time" --manifest "$MANIFEST" --references "$OUT/ref-lights" --anchor ch13-power \
        --csv "$DATA/bench_lights.csv" || exit 1
    # its record, for the table plots/lights_equal_time.table makes of it
    printf '%s\t%s\n' "$MODE" "make bench (part 5: bench_scenes --render many-lights.scene --lights tree|power --width $LIGHTS_WIDTH --threads 2, spp $LIGHTS_SPP, seeds $SEEDS; bench_equal_time --anchor ch13-power)" \
        > "$DATA/lights.run"
fi

echo
echo "== make bench ($MODE) took $(($(date +%s) - START)) s of wall time; load average now $(cut -d' ' -f1-3 /proc/loadavg)"
times > "$OUT/times.txt" # (in this shell: in a pipeline it would time a subshell)
echo "CPU time of everything it ran (user, system): $(tail -1 "$OUT/times.txt")"
