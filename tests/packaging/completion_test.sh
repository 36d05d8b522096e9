#!/bin/bash
# The bash completion the package installs (packaging/leakmon.bash-completion), driven as bash
# drives it: COMP_WORDS/COMP_CWORD set, the function called, COMPREPLY read back.
#   completion_test.sh BIN_DIR SOURCE_DIR SCRATCH_DIR
# (no `set -u`: bash-completion's own functions read unset variables)
bin_dir=$(realpath "$1") source_dir=$(realpath "$2") scratch=$3
export PATH="$bin_dir:$PATH"
# shellcheck disable=SC1091
source /usr/share/bash-completion/bash_completion
# shellcheck disable=SC1090,SC1091
source "$source_dir/packaging/leakmon.bash-completion"
failures=0

complete_line() {  # complete_line WORD...: COMPREPLY for the last word of `leakmon WORD...`
  COMP_WORDS=(leakmon "$@")
  COMP_CWORD=$((${#COMP_WORDS[@]} - 1))
  COMP_LINE="${COMP_WORDS[*]}"
  COMP_POINT=${#COMP_LINE}
  COMPREPLY=()
  _leakmon leakmon "${COMP_WORDS[COMP_CWORD]}" "${COMP_WORDS[COMP_CWORD - 1]}"
  printf '%s\n' "${COMPREPLY[@]}" | sort
}

expect() {  # expect "description" "expected lines" "actual lines"
  if [[ "$2" == "$3" ]]; then
    echo "ok   $1"
  else
    echo "FAIL $1: expected [$2], got [$3]"
    failures=$((failures + 1))
  fi
}

expect "subcommands" "probe" "$(complete_line pro)"
expect "subcommands starting with s" "$(printf 'sim\nstate\nstatus')" "$(complete_line s)"
expect "check-config's flags" "$(printf -- '--no-peers\n--no-probe')" \
  "$(complete_line check-config --no-p)"
expect "probe's options" "$(printf -- '--seconds')" "$(complete_line probe --se)"
mkdir -p "$scratch/dir" && touch "$scratch/dir/rig.yaml" "$scratch/dir/notes.txt"
cd "$scratch/dir" || exit 1
expect "a configuration file for --config" "rig.yaml" "$(complete_line probe --config '')"
expect "state's actions" "$(printf 'learn\nreset\nshow')" "$(complete_line state '')"
echo "$failures failure(s)"
exit $((failures > 0))
