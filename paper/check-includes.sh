#!/usr/bin/env bash
# Every file that paper/report.tex includes (\input, \includegraphics) exists. Run after
# `make figures`, which generates them. Exits 1 and names each missing file.
set -euo pipefail
cd "$(dirname "$0")"
missing=0
count=0
while read -r f; do
  count=$((count + 1))
  case "$f" in *.*) path="$f" ;; *) path="$f.tex" ;; esac
  if [ ! -s "$path" ]; then
    echo "paper/report.tex includes $f, which is missing or empty" >&2
    missing=1
  fi
done < <(grep -v '^\s*%' report.tex | grep -o '\\\(input\|includegraphics\)\(\[[^]]*\]\)\?{[^}]*}' | sed 's/.*{\(.*\)}/\1/')
if [ "$count" -eq 0 ]; then
  echo "found no includes in paper/report.tex" >&2
  exit 1
fi
[ "$missing" -eq 0 ] && echo "all $count files included by paper/report.tex exist"

# Every generated number (\res{exp:cell:field}) and setting (\setting{name}) the report quotes is
# defined: an undefined \csname expands to nothing, so a typo would vanish silently from the PDF.
keys=0
for kind in res setting; do
  files="generated/numbers.tex generated/presets.tex"
  [ "$kind" = setting ] && files=generated/settings.tex
  while read -r key; do
    keys=$((keys + 1))
    # shellcheck disable=SC2086
    if ! grep -qsF "\\csname $kind:$key\\endcsname" $files; then
      echo "paper/report.tex quotes \\$kind{$key}, which $files does not define" >&2
      missing=1
    fi
  done < <(grep -v '^\s*%' report.tex | grep -o "[\\]$kind{[^}]*}" | sed 's/.*{\(.*\)}/\1/' | sort -u)
done
[ "$missing" -eq 0 ] && echo "all $keys numbers and settings quoted by paper/report.tex are defined"
exit "$missing"
