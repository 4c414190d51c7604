#!/bin/sh
# splice.sh -- the numbers a chapter quotes come from the run that drew its
# figure. A README holds each measured table between two comments,
#
#   <!-- table ch11_equal_time -->
#   ...
#   <!-- end of table ch11_equal_time -->
#
# and the lines between them are DIR/NAME.md: the table that `make plots`
# wrote (plots/NAME.table, from the same CSV as plots/NAME.gp), with the
# command of the run that made the data. `make figures` splices the build's
# tables into the READMEs (and keeps a copy beside the committed figures,
# docs/img/NAME.md); `make test-docs` checks with --check that every README
# holds the committed copy, so that a table cannot be edited by hand.
#
#   docs/splice.sh [--check] DIR FILE...
set -eu
check=no
if [ "${1:-}" = --check ]; then check=yes; shift; fi
dir=${1:?usage: splice.sh [--check] DIR FILE...}
shift
status=0
for file in "$@"; do
    grep -q '^<!-- table [a-z0-9_]* -->$' "$file" || continue
    awk -v dir="$dir" -v file="$file" '
        /^<!-- table [a-z0-9_]* -->$/ {
            print
            name = $3
            path = dir "/" name ".md"
            if ((getline line < path) <= 0) {
                printf "%s:%d: no table %s (make plots writes it)\n", file, NR, path > "/dev/stderr"
                exit 2
            }
            print line
            while ((getline line < path) > 0) print line
            close(path)
            skipping = 1
            next
        }
        skipping && $0 == "<!-- end of table " name " -->" { skipping = 0 }
        !skipping { print }
        END { if (skipping) { printf "%s: table %s has no end comment\n", file, name > "/dev/stderr"; exit 2 } }
    ' "$file" > "$file.splice" || { rm -f "$file.splice"; exit 2; }
    if cmp -s "$file" "$file.splice"; then
        rm -f "$file.splice"
    elif [ $check = yes ]; then
        echo "$file: a measured table differs from the run that drew its figure ($dir):"
        diff "$file" "$file.splice" | head -20
        rm -f "$file.splice"
        status=1
    else
        mv "$file.splice" "$file"
        echo "spliced the tables of $dir into $file"
    fi
done
exit $status
