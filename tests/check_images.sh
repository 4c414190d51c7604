#!/bin/sh
# tests/check_images.sh FILE.md...: every image a markdown file shows,
# ![alt](path), must be a file in the repository (not under build/, which a
# clone does not have), so that the text reads with its pictures on any Git
# host. Prints file:line: what for each that is not, and fails. make
# test-docs runs it on every README and page source, and first on
# tests/docs/bad_missing_image.md, which it must refuse.
set -u
status=0
for md in "$@"; do
  dir=$(dirname "$md")
  grep -no '!\[[^]]*\]([^)]*)' "$md" | while IFS= read -r hit; do
    line=${hit%%:*}
    target=$(printf '%s\n' "${hit#*:}" | sed 's/.*](\([^)]*\))$/\1/')
    case $target in
      http://* | https://*) echo "$md:$line: $target is not in the repository (a remote image)"; echo x >&3 ;;
      *)
        path=$(realpath -m --relative-to=. "$dir/$target")
        case $path in
          build/* | ../*) echo "$md:$line: $target is $path, not a file of the repository"; echo x >&3 ;;
          *) [ -f "$path" ] || { echo "$md:$line: $target does not exist in the repository"; echo x >&3; } ;;
        esac ;;
    esac
  done 3>> "${TMPDIR:-/tmp}/check_images.$$"
done
if [ -s "${TMPDIR:-/tmp}/check_images.$$" ]; then status=1; fi
rm -f "${TMPDIR:-/tmp}/check_images.$$"
exit $status
