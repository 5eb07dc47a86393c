#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Checks of the repository as a product, on the tracked files of the source tree:
#   readme-length   README.md, the front page, has at most 250 lines;
#   process-words   no tracked file speaks of how the project was developed (numbered sessions or
#                   issues, reviews, the state a tree ended or began in). ParaView's own sessions
#                   (a pvpython, builtin or server session) are not numbered and do not match.
#                   Third-party licence texts (Data/licenses/) are not ours to edit.
# Exit 0: passed; 1: failed (the offending lines are printed); 77: not a git checkout (skipped).
# Usage: check_repository.sh <source dir> readme-length|process-words
set -uo pipefail
root=$1 check=$2
if ! git -C "$root" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  echo "$root is not a git checkout: the tracked files are unknown, check skipped"
  exit 77
fi
case "$check" in
  readme-length)
    limit=250
    lines=$(wc -l <"$root/README.md") || exit 1
    if [ "$lines" -gt "$limit" ]; then
      echo "README.md has $lines lines, more than $limit: move the detail to docs/"
      exit 1
    fi
    echo "README.md: $lines lines (at most $limit)"
    ;;
  process-words)
    # Bracketed letters keep this file from matching its own patterns.
    pattern='\bsessio[n]s? *#?[0-9]|\bissu[e]s? *#?[0-9]|\bthe revie[w]\b|\bfinal tre[e]\b|\bstarting cod[e]\b'
    found=$(git -C "$root" grep -n -I -i -E "$pattern" -- . ':(exclude)Data/licenses' || true)
    # File names too (result files named by session).
    names=$(git -C "$root" ls-files | grep -i -E "sessio[n][-_ ]?[0-9]|issu[e][-_ ]?[0-9]" || true)
    if [ -n "$found$names" ]; then
      echo "Development-process words in tracked files (say what the code does and why instead):"
      [ -n "$found" ] && echo "$found" | head -50
      [ -n "$names" ] && echo "$names" | sed 's/^/file name: /' | head -20
      echo "$(printf '%s\n' "$found" "$names" | grep -c .) line(s) in all"
      exit 1
    fi
    echo "no development-process words in $(git -C "$root" ls-files | wc -l) tracked files"
    ;;
  *)
    echo "usage: $0 <source dir> readme-length|process-words"
    exit 2
    ;;
esac
