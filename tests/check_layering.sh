#!/bin/bash
# check_layering.sh -- each chapter builds only on common/ and the chapters
# before it, the lecture's core in common/ on nothing of the program
# machinery beside it, and the includes say so.
#
#   tests/check_layering.sh [BUILD_DIR]   this repository (run by `make test`; BUILD_DIR unused)
#   tests/check_layering.sh --tree DIR    the tree at DIR only
#
# The rules, for every `#include "..."` (and `#include <NN-name/...>`):
#   - chapters/NN-name/ (.c, .h, .inc) includes only common/ headers and
#     headers of chapters NN and before;
#   - common/ includes no chapter header, nor do the suites and fuzz targets
#     of common/ (tests/test_*.c but test_chNN.c, tests/fuzz_*.c), which
#     link common/ only;
#   - common/core/ (the lecture's core) includes only headers of
#     common/core/, never one of common/program/ (the machinery: flags,
#     files, scene format, MPI, checkpoints), which may include both;
#   - tests/test_chNN.c includes only chapters NN and before, also through
#     the helpers in tests/ it includes (accel_check.h, ...);
#   - one style: a chapter's header is always "NN-name/file.h", also within
#     its own chapter (never a bare "file.h", never ../); a common header
#     is "file.h", whichever folder of common/ holds it (the build has
#     -Icommon/core -Icommon/program); a helper of tests/ is "file.h" from
#     tests/.
# tests/bench_*.c and docs/figures/*.c may use every chapter (they link
# them all); their includes keep the style.
#
# Prints every violation as FILE:LINE: WHAT and exits 1 if there is any.
# Before the repository, it checks a small tree it writes with one
# violation of each kind beside clean files, and fails unless it reports
# exactly those: so it cannot pass by checking nothing.
set -u

# check_tree DIR: prints the violations in DIR; status 1 if any.
check_tree() {
    local root=$1
    local -A exists=()
    local f
    while IFS= read -r f; do exists[$f]=1; done < <(
        cd "$root" && find chapters common tests -maxdepth 2 -type f 2>/dev/null)
    violations=0
    files=0
    local file level
    for file in $(cd "$root" && ls -d chapters/[0-9][0-9]-*/*.[ch] chapters/[0-9][0-9]-*/*.inc \
        common/*/*.[ch] tests/*.[ch] docs/figures/*.c 2>/dev/null); do
        case $file in
        chapters/*) level=${file#chapters/}; level=$((10#${level%%-*})) ;;
        common/* | tests/fuzz_*.c) level=0 ;;
        tests/test_ch[0-9][0-9].c) level=${file#tests/test_ch}; level=$((10#${level%.c})) ;;
        tests/test_*.c) level=0 ;;
        *) level=99 ;; # tests/*.h (checked through what includes them), benchmarks, figures
        esac
        files=$((files + 1))
        check_file "$root" "$file" "$level"
    done
    [ $violations -eq 0 ]
}

# check_file ROOT FILE LEVEL [WHO AT VIA]: the includes of FILE, under the
# rules of level LEVEL (a chapter's number; 0 for common/, 99 for anything).
# When FILE is a helper of tests/ that the suite WHO includes at line AT
# (through the helpers VIA), only its chapter headers count, against WHO's
# level; its style was checked on FILE itself.
check_file() {
    local root=$1 file=$2 level=$3 who=${4:-} at=${5:-} via=${6:-}
    local dir=${file%/*} line text name angle num what where
    while IFS= read -r line; do
        text=${line#*:}
        line=${line%%:*}
        if [[ $text =~ ^[[:space:]]*#[[:space:]]*include[[:space:]]*\"([^\"]*)\" ]]; then
            name=${BASH_REMATCH[1]} angle=0
        elif [[ $text =~ ^[[:space:]]*#[[:space:]]*include[[:space:]]*\<([0-9][0-9]-[^/\>]*/[^\>]*)\> ]]; then
            name=${BASH_REMATCH[1]} angle=1
        else
            continue
        fi
        what=""
        if [[ $name =~ ^[0-9][0-9]-[^/]+/[^/]+$ ]]; then # a chapter's header
            num=$((10#${name%%-*}))
            if [ -n "$via" ]; then
                where="through \"${via// /\", \"}\""
            else
                where=""
            fi
            if [ -z "$via" ] && [ $angle = 1 ]; then
                what="includes <$name>: a chapter's header is included as \"$name\""
            elif [ -z "${exists[chapters/$name]:-}" ]; then
                [ -n "$via" ] || what="includes \"$name\", which is not a file of chapters/"
            elif [ "$num" -gt "$level" ]; then
                local n=$(printf %02d "$level")
                case ${who:-$file} in
                common/*) what="includes \"$name\": common/ includes no chapter's header" ;;
                tests/test_ch*) what="includes \"$name\"${where:+ $where}: a suite of chapter $n includes chapters up to $n only" ;;
                tests/*) what="includes \"$name\"${where:+ $where}: a suite or fuzz target of common/ includes no chapter's header" ;;
                *) what="includes \"$name\": chapter $n includes only common/ and chapters up to $n" ;;
                esac
            fi
        elif [ -n "$via" ]; then # in a helper: only the helpers it includes matter
            if [[ $name != */* && -n "${exists[tests/$name]:-}" && " $via " != *" $name "* ]]; then
                check_file "$root" "tests/$name" "$level" "$who" "$at" "$via $name"
            fi
        elif [[ $name == */* ]]; then
            if [[ $name == *..* || $name == ./* || $name == /* ]]; then
                what="includes \"$name\": no relative paths; a chapter's header is \"NN-name/file.h\", a common one \"file.h\""
            else
                what="includes \"$name\", which is neither a chapter's \"NN-name/file.h\" nor a common \"file.h\""
            fi
        elif [[ $file == chapters/* && -n "${exists[$dir/$name]:-}" ]]; then
            what="includes \"$name\": its own chapter's header is included as \"${dir#chapters/}/$name\""
        elif [ -n "${exists[common/core/$name]:-}" ]; then
            :
        elif [ -n "${exists[common/program/$name]:-}" ]; then
            [[ $file != common/core/* ]] ||
                what="includes \"$name\", which is common/program/'s: the core includes no machinery header"
        elif [[ $file == tests/* && -n "${exists[tests/$name]:-}" ]]; then
            # A helper of tests/: the chapter headers it includes count for this suite.
            [ "$level" -ge 99 ] || check_file "$root" "tests/$name" "$level" "$file" "$line" "$name"
        else
            what="includes \"$name\", which is not a header of common/$([[ $file == tests/* ]] && echo " or tests/")"
        fi
        if [ -n "$what" ]; then
            echo "${who:-$file}:${at:-$line}: $what"
            violations=$((violations + 1))
        fi
    done < <(grep -n -E '^[[:space:]]*#[[:space:]]*include' "$root/$file")
}

# A tree with one violation of each kind, each marked BAD with the text the
# report must contain; every other include in it is allowed.
self_test() {
    local t
    t=$(mktemp -d "${TMPDIR:-/tmp}/check_layering.XXXXXX")
    self_test_dir=$t
    trap 'rm -rf "$self_test_dir"' EXIT
    mkdir -p "$t/common/core" "$t/common/program" "$t/chapters/01-first" "$t/chapters/02-second" "$t/tests" "$t/docs/figures"
    printf '%s\n' '#include <stdio.h>' '#include "vec.h"' > "$t/common/core/vec.h"
    printf '%s\n' '#include "vec.h"' '#include "flags.h" // BAD the core includes no machinery' > "$t/common/core/vec.c"
    printf '%s\n' '#include "vec.h"' > "$t/common/program/flags.h"
    printf '%s\n' '#include "flags.h"' '#include "vec.h"' '#include "02-second/b.h" // BAD common/ includes no chapter' \
        > "$t/common/program/util.c"
    printf '%s\n' '#include "vec.h"' > "$t/chapters/01-first/a.h"
    printf '%s\n' '#include "01-first/a.h"' '#include "a.h" // BAD its own chapter' \
        '#include "02-second/b.h" // BAD chapters up to 01' '#include "../02-second/b.h" // BAD no relative paths' \
        '#include <01-first/a.h> // BAD included as' '#include "01-first/missing.h" // BAD not a file of chapters/' \
        '#include "nothing.h" // BAD not a header of common/' > "$t/chapters/01-first/a.c"
    printf '%s\n' '#include "01-first/a.h"' '#include "vec.h"' '#include <stdlib.h>' > "$t/chapters/02-second/b.h"
    printf '%s\n' '#include "02-second/b.h"' '  #  include "01-first/a.h"' > "$t/chapters/02-second/b.c"
    printf '%s\n' '#include "02-second/b.h"' '#include "vec.h"' > "$t/tests/helper.h"
    printf '%s\n' '#include "helper.h" // BAD through "helper.h"' '#include "01-first/a.h"' > "$t/tests/test_ch01.c"
    printf '%s\n' '#include "helper.h"' '#include "02-second/b.h"' '#include <cmocka.h>' > "$t/tests/test_ch02.c"
    printf '%s\n' '#include "vec.h"' '#include "01-first/a.h" // BAD suite or fuzz target of common/' > "$t/tests/test_vec.c"
    printf '%s\n' '#include "helper.h"' '#include "02-second/b.h"' > "$t/tests/bench_all.c"
    printf '%s\n' '#include "02-second/b.h"' '#include "vec.h"' > "$t/docs/figures/fig.c"
    local out status missing=0 want got file line rest expect
    out=$(check_tree "$t")
    status=$?
    got=$(echo "$out" | grep -c .)
    want=0
    while IFS=: read -r file line rest; do
        want=$((want + 1))
        expect=${rest#*// BAD }
        if ! echo "$out" | grep -F -- "$file:$line: " | grep -q -F -- "$expect"; then
            echo "check_layering: self-test: $file:$line is not reported with '$expect'"
            missing=$((missing + 1))
        fi
    done < <(cd "$t" && grep -rn '// BAD ' --include='*.[ch]' . | sed 's|^\./||')
    if [ $status -ne 1 ] || [ $missing -ne 0 ] || [ "$got" -ne "$want" ]; then
        echo "check_layering: self-test FAILED: exit status $status (want 1), $got violations reported (want $want):"
        echo "$out" | sed 's/^/    /'
        return 1
    fi
    echo "check_layering: self-test: the $want violations of a bad tree are found"
}

if [ "${1:-}" = --tree ]; then
    check_tree "${2:?usage: check_layering.sh --tree DIR}"
    status=$?
    echo "check_layering: $files files, $violations violations"
    exit $status
fi
self_test || exit 1
root=$(cd "$(dirname "$0")/.." && pwd)
check_tree "$root"
status=$?
echo "check_layering: $files files, $violations violations"
exit $status
