#!/bin/bash
# tests/exercise_tool.sh BUILD: tools/exercise.py keeps every learner's work.
# On a copy of the tree (a git repository of its own, so "the reference"
# is its HEAD), without compiling anything:
#   1. make exercise CH=09 writes stubs, the handed-out files no longer hold
#      the reference bodies, and the tool reads its stubs back as stubs;
#   2. a half-written body (the stub's call still in it) is the learner's:
#      handing out again keeps it, byte for byte;
#   3. make solution gives every file back as HEAD has it, and keeps the
#      learner's body in .exercises/yours/;
#   4. handing out again brings the learner's body back, not a new stub;
#   5. a second solution with another body keeps both versions;
#   6. a missing end marker is refused, naming the file and line, and
#      nothing is written.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
tree=$(mktemp -d "${TMPDIR:-/tmp}/exercise_tool.XXXXXX")
trap 'rm -rf "$tree"' EXIT
fails=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAILED: $1"; fails=$((fails + 1)); fi; }

(cd "$root" && git ls-files -z --cached --others --exclude-standard -- common chapters tools Makefile mk |
  grep -zv '^\.exercises/' | xargs -0 cp --parents -t "$tree")
cd "$tree" && git init -q && git add -A && git -c user.name=t -c user.email=t@localhost commit -qm tree || exit 1
tool="python3 tools/exercise.py"
file=chapters/09-path-tracing/path_tracer.c

$tool handout --ch 09 > out.txt 2>&1
check "handing out writes stubs" "grep -q 'exercise_todo(\"shade\"' $file"
check "a handed-out file holds no reference body" "! grep -q 'vec3 l_q = hit ? shade(pt' $file"
$tool status > status.txt 2>&1
check "and the tool sees its own stubs as stubs" "grep -q '^shade  *stub ' status.txt && grep -q '^light_sample  *stub ' status.txt"

# The learner starts: one line under the stub's call.
sed -i '/exercise_todo("shade"/a\    vec3 l_dir_mine = vec3_splat(0.0f); /* mine */' $file
cp $file half.c
$tool handout --ch 09 > out.txt 2>&1
check "handing out again keeps a half-written body" "cmp -s $file half.c"
check "and says so" "grep -q 'shade .*your version is there, kept' out.txt"

$tool solution --ch 09 > out.txt 2>&1
check "make solution gives the files back as committed" "git diff --quiet -- chapters common"
check "and keeps the learner's body" "grep -q 'l_dir_mine' .exercises/yours/$file/shade.c"

$tool handout --ch 09 > out.txt 2>&1
check "handing out again brings the learner's body back" "grep -q 'l_dir_mine' $file"
check "and the other exercise's stub" "grep -q 'exercise_todo(\"light_sample\"' chapters/09-path-tracing/light_transport.c"

sed -i 's|/\* mine \*/|/* mine, second try */|' $file
$tool solution --ch 09 > out.txt 2>&1
check "a second version is kept beside the first" \
  "grep -q 'second try' .exercises/yours/$file/shade.c && grep -q 'l_dir_mine' .exercises/yours/$file/shade.1.c"
check "and the files are as committed again" "git diff --quiet -- chapters common"
check "and no copy of a reference is left to go stale" "[ -z \"\$(find .exercises/reference -type f 2>/dev/null)\" ]"

sed -i '/end of exercise shade/d' $file
cp $file broken.c
$tool handout --ch 09 > out.txt 2>&1
status=$?
check "a missing end marker is refused" "[ $status -ne 0 ] && grep -q 'path_tracer.c:[0-9]*: exercise shade has no' out.txt"
check "and nothing is written" "cmp -s $file broken.c && git diff --quiet -- chapters/09-path-tracing/light_transport.c"

echo "exercise_tool: $fails failed"
[ $fails -eq 0 ]
