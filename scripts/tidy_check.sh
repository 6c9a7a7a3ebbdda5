#!/usr/bin/env bash
# Runs clang-tidy (Debian's, 14) with the checks of .clang-tidy on what a change touches,
# as scripts/format_check.sh does for layout: the .cpp files that differ from REV (default
# HEAD) in the working tree, staged or not, outside tests/ (a new file counts once it is
# added, or `git add -N`), with findings kept only on the lines the change adds or edits
# there and in the changed headers they include (clang-tidy's --line-filter). Exits 1 with
# the findings if there are any.
#   scripts/tidy_check.sh [REV]          the lines changed since REV
#   scripts/tidy_check.sh --all          every product source, every line (about 70 s a
#                                        file on this machine: over an hour for the tree)
# The compile commands come from build-tidy/, configured (not built) here without unity
# batches, since build/'s compile_commands.json names batch files, not sources.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
command -v clang-tidy >/dev/null 2>&1 ||
  { echo "tidy_check: expected clang-tidy (Debian's clang-tidy package; scripts/setup.sh --test installs it), found none" >&2; exit 1; }

product='^(app|bench|discretizers|environments|framework|learners|python|rewards)/.*\.cpp$'
if [ "${1:-}" = "--all" ]; then
  mapfile -t files < <(git ls-files | grep -E "$product" || true)
  what="every product source"
else
  rev="${1:-HEAD}"
  git rev-parse --verify -q "$rev^{commit}" >/dev/null ||
    { echo "tidy_check: expected a commit to compare with, found '$rev'" >&2; exit 1; }
  mapfile -t files < <(git diff --name-only --diff-filter=d "$rev" -- | grep -E "$product" || true)
  what="the C++ lines changed since $rev"
  # The changed lines of every changed C++ file, as clang-tidy's line filter; a framework
  # header is seen through the build's include tree (mgrl/<stage>/), so it is named both ways.
  filter="$(git diff -U0 --diff-filter=d "$rev" -- '*.cpp' '*.hpp' | /usr/bin/python3 -c '
import json, re, sys
ranges, name = {}, None
for line in sys.stdin:
    if line.startswith("+++ "):
        name = line[6:].strip() if line.startswith("+++ b/") else None
    elif line.startswith("@@") and name:
        m = re.match(r"@@ -\S+ \+(\d+)(?:,(\d+))? @@", line)
        start, count = int(m.group(1)), int(m.group(2) or 1)
        if count > 0:
            ranges.setdefault(name, []).append([start, start + count - 1])
out = []
for name, lines in ranges.items():
    out.append({"name": "/" + name, "lines": lines})
    if name.startswith("framework/"):
        out.append({"name": "/mgrl/" + name[len("framework/"):], "lines": lines})
print(json.dumps(out, separators=(",", ":")))
')"
  # Only deletions: nothing to look at.
  [ "$filter" = "[]" ] && files=()
fi
if [ "${#files[@]}" -eq 0 ]; then
  echo "tidy_check: no C++ source to check ($what: none)" >&2
  exit 0
fi

build="$root/build-tidy"
mkdir -p "$build"
if [ ! -f "$build/compile_commands.json" ] || [ "$root/CMakeLists.txt" -nt "$build/compile_commands.json" ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DMGRL_UNITY=OFF \
    -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >"$build/configure.log" 2>&1 ||
    { cat "$build/configure.log" >&2; echo "tidy_check: configuring $build failed (above)" >&2; exit 1; }
fi
# A source CMake does not compile (a new file not yet in a CMakeLists.txt) has no command.
missing=()
for f in "${files[@]}"; do
  grep -q "\"file\": \"$root/$f\"" "$build/compile_commands.json" || missing+=("$f")
done
if [ "${#missing[@]}" -gt 0 ]; then
  cmake "$build" >"$build/configure.log" 2>&1 || true  # a source added since the last configure
  still=()
  for f in "${missing[@]}"; do
    grep -q "\"file\": \"$root/$f\"" "$build/compile_commands.json" || still+=("$f")
  done
  if [ "${#still[@]}" -gt 0 ]; then
    echo "tidy_check: expected each changed source in a CMakeLists.txt, found none for: ${still[*]}" >&2
    exit 1
  fi
fi

jobs="${TIDY_JOBS:-$(nproc)}"
echo "tidy_check: ${#files[@]} file(s), $what, $jobs at a time" >&2
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
status=0
printf '%s\n' "${files[@]}" |
  xargs -P "$jobs" -I{} sh -c 'clang-tidy --quiet ${4:+--line-filter="$4"} -p "$1" "$2" >"$3.$$" 2>&1 || { cat "$3.$$"; echo "FAILED $2"; }; rm -f "$3.$$"' \
    _ "$build" {} "$log" "${filter:-}" >"$log.all" || status=1
if grep -q "^FAILED " "$log.all"; then status=1; fi
if ((status)); then
  grep -v "^[0-9]* warnings\? generated\.$\|^Suppressed \|^Use -header-filter" "$log.all" || true
  echo "tidy_check: expected no clang-tidy findings in $what, found the ones above (fix them, or NOLINT(check) with why)" >&2
  rm -f "$log.all"
  exit 1
fi
rm -f "$log.all"
echo "tidy_check: $what pass .clang-tidy's checks" >&2
