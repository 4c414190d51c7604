#!/bin/sh
# excerpts.sh -- the code a README shows is the code of the source. Each
# excerpt in a README is a C code block between two comments,
#
#   <!-- excerpt chapters/09-path-tracing/path_tracer.c shade -->
#   `shade`, from [`chapters/09-path-tracing/path_tracer.c`](path_tracer.c):
#
#   ```c
#   ...the definition of shade, its leading comment included...
#   ```
#   <!-- end of excerpt -->
#
# so that a README read on any Git host shows the code, and names where it
# comes from. Everything between the comments is written by this script
# from the source (docs/excerpts.awk finds the definition as the book's
# weave, docs/weave.lua, does): `make excerpts` writes every README again
# (a block ```excerpt with lines "FILE NAME" becomes such excerpts), and
# writes only the ones that changed, so it can be run again after any
# merge. With --check it writes nothing and fails, naming the README's
# line, the name and the source, where an excerpt differs from its source
# (tests/check_excerpts.sh, in `make test` and `make test-docs`).
#
#   docs/excerpts.sh [--check] FILE...     (FILE from the repository's root)
#
# Exit status: 0 all in line (or written), 1 --check found a difference,
# 2 an excerpt names a file or definition that does not exist.
set -eu
check=0
if [ "${1:-}" = --check ]; then check=1; shift; fi
awk_program=$(dirname "$0")/excerpts.awk
# While a learner has exercises handed out (make exercise), the sources hold
# stubs: the READMEs show, and are checked against, the reference bodies,
# from a copy of the tree that tools/exercise.py keeps with them.
source_root=
if [ -d .exercises ] && python3 tools/exercise.py handed-out; then
    source_root=build/reference/src/
    python3 tools/exercise.py reference-tree "$source_root"
fi
status=0
for file in "$@"; do
    grep -q -e '^<!-- excerpt ' -e '^```excerpt' "$file" || continue
    out=$(mktemp)
    rc=0
    awk -v file="$file" -v check=$check -v source_root="$source_root" -f "$awk_program" "$file" > "$out" || rc=$?
    if [ $rc = 2 ]; then
        rm -f "$out"; status=2; continue
    fi
    if [ $check = 1 ]; then
        [ $rc = 0 ] || { [ $status = 2 ] || status=1; }
    elif ! cmp -s "$file" "$out"; then
        cat "$out" > "$file.excerpts" && mv "$file.excerpts" "$file"
        echo "excerpts: wrote $file from its sources"
    fi
    rm -f "$out"
done
exit $status
