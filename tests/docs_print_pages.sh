#!/bin/sh
# tests/docs_print_pages.sh MAX PAGE.html...: prints each page to PDF in
# headless Chromium ($CHROMIUM: the command and its flags), as a reader who
# prints the chapter would (A4, the book's print style), and counts the PDF's
# pages (its /Type /Page objects, which Chromium writes uncompressed). Fails
# when a page takes more than MAX. make test-docs runs it on every chapter
# page, and first on tests/docs/bad_long_page.html, which it must refuse.
set -u
max=$1
shift
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
status=0
for page in "$@"; do
  name=$(basename "$page" .html)
  # shellcheck disable=SC2086  # $CHROMIUM is a command with its flags
  $CHROMIUM --no-pdf-header-footer --print-to-pdf="$tmp/$name.pdf" "file://$(realpath "$page")" \
    > /dev/null 2>> "$tmp/chromium.log"
  if ! [ -s "$tmp/$name.pdf" ]; then
    echo "FAIL $page: Chromium printed no PDF"
    status=1
    continue
  fi
  n=$(grep -ao '/Type */Page\b' "$tmp/$name.pdf" | wc -l)
  if [ "$n" -gt "$max" ]; then
    echo "FAIL $page: $n printed pages (A4), more than $max"
    status=1
  else
    echo "$name: $n printed pages"
  fi
done
exit $status
