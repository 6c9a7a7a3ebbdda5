#!/usr/bin/env bash
# Holds the C++ lines a change touches to .clang-format (clang-format 14, Debian's): the
# lines that differ from REV (default HEAD) in the working tree, staged or not, in tracked
# files (a new file counts once it is added, or `git add -N`). The rest of the tree keeps
# its hand-written layout. Prints clang-format's diff and exits 1 if a touched line is off;
# `git add` the files and `git clang-format REV` applies it.
#   scripts/format_check.sh [REV]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
rev="${1:-HEAD}"
cd "$root"
command -v git-clang-format >/dev/null 2>&1 ||
  { echo "format_check: expected git-clang-format (Debian's clang-format package; scripts/setup.sh --test installs it), found none" >&2; exit 1; }
git rev-parse --verify -q "$rev^{commit}" >/dev/null ||
  { echo "format_check: expected a commit to compare with, found '$rev'" >&2; exit 1; }
out="$(git clang-format --diff --extensions cpp,hpp "$rev" -- 2>&1 || true)"
case "$out" in
  "" | "no modified files to format" | "clang-format did not modify any files")
    echo "format_check: the C++ lines changed since $rev follow .clang-format" >&2 ;;
  *)
    printf '%s\n' "$out"
    echo "format_check: expected the C++ lines changed since $rev to follow .clang-format, found the differences above (git add the files, then git clang-format $rev applies them)" >&2
    exit 1 ;;
esac
