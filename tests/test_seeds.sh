#!/bin/sh
# test_seeds.sh -- every random test of every suite, over SEEDS other seeds.
#
#   tests/test_seeds.sh BUILD_DIR [SEEDS] [JOBS] [PATTERN]     (make test-seeds)
#
# A test is "random" if it asks test_seed() (tests/test_support.h) for its
# seed: one run of each suite with TEST_SEED_TRACE set lists them, so the
# list cannot drift from the code. Each is then run alone (TEST_FILTER) with
# TEST_SEED_OFFSET = 1 .. SEEDS, JOBS at a time, and the script prints, per
# test, how many of the SEEDS runs failed. The thresholds are set so that a
# correct implementation fails a test with probability about 1e-6 or less:
# over 200 seeds the expected count is 0, and any failure is worth reading.
# PATTERN (an extended regular expression) keeps only the tests whose names
# it matches, anywhere in the name. Exit status 1 if any run failed, or if
# the pattern keeps no test (a typo must not pass as "0 failures").
set -u
build=${1:?usage: test_seeds.sh BUILD_DIR [SEEDS] [JOBS]}
seeds=${2:-200}
jobs=${3:-2}
pattern=${4:-.}
work=$build/seeds
rm -rf "$work"
mkdir -p "$work"

# 1. Which tests draw random numbers, suite by suite.
: > "$work/tests"
for suite in "$build"/tests/test_*; do
    case $suite in *.log | *.d) continue ;; esac
    [ -x "$suite" ] || continue
    TEST_SEED_TRACE=1 "$suite" 2>&1 | awk -v suite="$suite" '
        /^\[ RUN      \] / { name = $4 }
        /^test_seed: used/ && name != "" && !(name in seen) { seen[name] = 1; print suite, name }' >> "$work/tests"
done
awk -v p="$pattern" '$2 ~ p' "$work/tests" > "$work/tests.kept"
mv "$work/tests.kept" "$work/tests"
count=$(wc -l < "$work/tests")
if [ "$count" -eq 0 ]; then
    echo "test-seeds: no random test's name matches '$pattern'" >&2
    exit 1
fi
echo "$count random tests, $seeds seeds each, $jobs at a time"

# 2. One line per (test, seed): run it, record failures.
while read -r suite name; do
    s=1
    while [ "$s" -le "$seeds" ]; do
        echo "$suite $name $s"
        s=$((s + 1))
    done
done < "$work/tests" | SEEDS_WORK=$work xargs -P "$jobs" -L 1 sh -c '
    suite=$1 name=$2 seed=$3 work=$SEEDS_WORK
    if TEST_FILTER="$name" TEST_SEED_OFFSET="$seed" "$suite" > "$work/$name.$seed.log" 2>&1; then
        rm -f "$work/$name.$seed.log"
    else
        echo "$name $seed" >> "$work/failures.$$"
    fi' run_one_seed

# 3. The table.
cat "$work"/failures.* 2>/dev/null > "$work/failures" || true
total=0
printf '%-78s %s\n' "test (suite)" "failed of $seeds"
while read -r suite name; do
    f=$(awk -v n="$name" '$1 == n' "$work/failures" | wc -l)
    total=$((total + f))
    printf '%-78s %d\n' "$name ($(basename "$suite"))" "$f"
done < "$work/tests"
echo "$total failures in $((count * seeds)) runs (logs of failing runs: $work/NAME.SEED.log)"
[ "$total" -eq 0 ]
