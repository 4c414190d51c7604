#!/bin/sh
# check_catalog.sh -- every test that docs/hard-cases.md names must exist.
#
#   tests/check_catalog.sh [BUILD_DIR]     (run by `make test`; BUILD_DIR unused)
#
# The catalog names tests as `tests/FILE.c: test_name` (and scripts as
# `tests/NAME.sh`). For each, the function must be defined in that file
# ("static void test_name(void **state)") and registered with cmocka
# ("cmocka_unit_test(test_name)"), so that it runs; a script must exist.
# Also fails if the catalog names no tests at all (a broken pattern).
set -u
here=$(dirname "$0")
catalog=$here/../docs/hard-cases.md
[ -f "$catalog" ] || { echo "check_catalog: $catalog is missing"; exit 1; }
missing=0
count=0
# Entries may wrap across lines in the Markdown; join the text first.
refs=$(tr '\n' ' ' < "$catalog" | grep -o 'tests/[a-z0-9_]*\.c: *test_[a-z0-9_]*' | sed 's/: */ /' | sort -u)
for_each_ref() {
    echo "$refs" | while read -r file name; do
        [ -n "$file" ] || continue
        path=$here/../$file
        if [ ! -f "$path" ]; then
            echo "check_catalog: docs/hard-cases.md names $file, which does not exist"
            echo x
        elif ! grep -q "^static void $name(void \*\*state)" "$path"; then
            echo "check_catalog: docs/hard-cases.md names $name, not defined in $file"
            echo x
        elif ! grep -q "cmocka_unit_test($name)" "$path"; then
            echo "check_catalog: $name is defined in $file but not registered (it never runs)"
            echo x
        fi
    done
}
out=$(for_each_ref)
missing=$(echo "$out" | grep -c '^x$')
echo "$out" | grep -v '^x$' | grep . 
count=$(echo "$refs" | grep -c .)
for script in $(tr '\n' ' ' < "$catalog" | grep -o 'tests/[a-z0-9_]*\.sh' | sort -u); do
    count=$((count + 1))
    if [ ! -f "$here/../$script" ]; then
        echo "check_catalog: docs/hard-cases.md names $script, which does not exist"
        missing=$((missing + 1))
    fi
done
if [ "$count" -lt 10 ]; then
    echo "check_catalog: only $count tests named in docs/hard-cases.md: is the pattern broken?"
    exit 1
fi
echo "hard-case catalog: $count tests named, $missing missing"
[ "$missing" -eq 0 ]
