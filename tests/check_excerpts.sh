#!/bin/sh
# check_excerpts.sh -- every excerpt a README shows is the code of its
# source (docs/excerpts.sh --check), and the check refuses one edited by hand.
#
#   tests/check_excerpts.sh BUILD_DIR     (run by `make test` and `make test-docs`)
#
# First the twin, a README of one excerpt made in BUILD_DIR/tests/: written
# by docs/excerpts.sh, it passes the check and a second run changes
# nothing; one line of its code changed by hand, the check refuses it,
# naming that line and the function. Then every README of the repository.
set -u
here=$(dirname "$0")
cd "$here/.." || exit 1
build=${1:-build}
dir=$build/tests/excerpt_twin
rm -rf "$dir"
mkdir -p "$dir"
twin=$dir/README.md
failed=0
fail() { echo "FAIL: $*"; failed=1; }

printf '# A twin\n\n<!-- excerpt common/core/camera.c camera_ray -->\n<!-- end of excerpt -->\n\nafter\n' > "$twin"
docs/excerpts.sh "$twin" > /dev/null || fail "docs/excerpts.sh could not fill $twin in"
grep -q '^ray camera_ray(' "$twin" || fail "the twin's excerpt does not hold camera_ray's code"
docs/excerpts.sh --check "$twin" 2> "$dir/check.txt" || fail "the check refuses the excerpt it wrote: $(cat "$dir/check.txt")"
cp "$twin" "$dir/again.md"
docs/excerpts.sh "$twin" > /dev/null
cmp -s "$twin" "$dir/again.md" || fail "a second docs/excerpts.sh changed $twin (not idempotent)"

# the hand edit: the last line of its code (the line above the closing fence)
line=$(awk '/^<!-- end of excerpt -->$/ { print NR - 2; exit }' "$twin")
sed "${line}s/\$/ \/\* edited by hand \*\//" "$twin" > "$dir/edited.md" && mv "$dir/edited.md" "$twin"
if docs/excerpts.sh --check "$twin" 2> "$dir/check.txt"; then
    fail "a hand-edited excerpt ($twin:$line) passed the check"
elif ! grep -q "^$twin:$line: camera_ray (from common/core/camera.c): the excerpt differs" "$dir/check.txt"; then
    cat "$dir/check.txt"
    fail "the check did not name $twin:$line and camera_ray"
else
    echo "ok: a hand-edited excerpt is refused: $(cat "$dir/check.txt")"
fi

# every README
if docs/excerpts.sh --check README.md docs/*.md chapters/*/*.md; then
    echo "ok: $(cat README.md docs/*.md chapters/*/*.md | grep -c '^<!-- excerpt ') excerpts in the READMEs are their sources' code"
else
    fail "an excerpt differs from its source (above): make excerpts"
fi
exit $failed
