#!/bin/sh
# check_measured_numbers.sh -- a chapter quotes no time it did not measure
# in this build. Times and speeds move with the machine and its load, so
# the chapters quote them only from a run: in a measured table (between
# "<!-- table NAME -->" and its end, docs/splice.sh, made by `make plots`)
# or a figure's caption. Anywhere else in a chapter's prose, outside code
# blocks and excerpts, a number followed by a unit of time or of speed
# (s, ms, µs, ns, seconds, minutes, CPU-s, Mrays/s, ...) is refused with
# its file and line. A page that is a record of measurements made once (a
# chapter's appendix of what did not pay) says so in its first line,
# "<!-- a record: ... -->", and is not checked.
#
#   tests/check_measured_numbers.sh [FILE...]   (no file, or a build
#   directory as `make test` passes it: every chapters/*/*.md)
# Before the files, it checks tests/docs/typed_time.md, which holds
# one such number, and fails unless that is refused: it cannot pass by
# checking nothing.
set -u

# check FILE: prints each time typed by hand as FILE:LINE: TEXT; status 1 if any.
check() {
    head -n 1 "$1" | grep -q '^<!-- a record: ' && return 0
    awk -v file="$1" '
        /^```/ { fenced = !fenced; next }
        /^<!-- (table|excerpt) / { region = 1; next }
        /^<!-- end of (table|excerpt)/ { region = 0; next }
        fenced || region { next }
        /[0-9]([0-9.,]*[0-9])?( | )(s|ms|µs|ns|seconds?|minutes?|hours?|CPU-s|CPU-seconds|Mrays\/s|rays\/s)([^A-Za-z0-9_]|$)/ {
            printf "%s:%d: a time typed by hand (quote it from a run: a measured table): %s\n", file, NR, $0
            bad = 1
        }
        END { exit bad }
    ' "$1"
}

dir=$(dirname "$0")
if check "$dir/docs/typed_time.md" > /dev/null; then
    echo "FAIL: tests/docs/typed_time.md, which types a time by hand, passed the check"
    exit 1
fi
if [ $# -eq 0 ] || [ -d "$1" ]; then
    set -- "$dir"/../chapters/*/*.md
fi
status=0
for f in "$@"; do check "$f" || status=1; done
[ $status -eq 0 ] && echo "ok: the chapters quote no time typed by hand ($# pages; tests/docs/typed_time.md is refused)"
exit $status
