#!/bin/sh
# man-page.sh BINARY HELP2MAN INCLUDE OUT: leakmon(1) from `leakmon --help`, the hand-written
# sections in INCLUDE and every subcommand's own --help (section SUBCOMMANDS).
set -eu
binary=$1 help2man=$2 include=$3 out=$4
sections=$(mktemp)
trap 'rm -f "$sections"' EXIT
cat "$include" >"$sections"
printf '[SUBCOMMANDS]\n' >>"$sections"
for sub in $("$binary" --help | sed -n 's/^  \([a-z][a-z-]*\)  .*/\1/p'); do
  printf '.SS %s\n.nf\n' "$sub"
  # roff: a backslash is written \e, and a line may not start with a control character.
  "$binary" "$sub" --help | sed -e 's/\\/\\e/g' -e "s/^\\([.']\\)/\\\\\\&\\1/"
  printf '.fi\n'
done >>"$sections"
"$help2man" --no-info --section 1 --name "internal-leakage monitor for hydraulic actuators" \
  --include "$sections" --output "$out" "$binary"
