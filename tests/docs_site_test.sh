#!/usr/bin/env bash
# The documentation site: mkdocs build --strict passes on the repository's docs, and fails on
# a broken link, a page no navigation entry reaches, and a missing picture; the site loads
# nothing from the network.
# Usage: tests/docs_site_test.sh SOURCE_DIR
set -euo pipefail
source="$(cd "$1" && pwd)"
work="$(mktemp -d /tmp/mgrl-docs-test.XXXXXX)"
trap 'rm -rf "$work"' EXIT
fail() {
  echo "docs_site_test: FAIL: $*" >&2
  exit 1
}
command -v mkdocs >/dev/null || fail "expected mkdocs (Debian's mkdocs: scripts/setup.sh --test installs it), found none"

(cd "$source" && mkdocs build --strict --quiet -d "$work/site") >"$work/build.log" 2>&1 ||
  { cat "$work/build.log" >&2; fail "mkdocs build --strict on the repository's docs"; }
pages=$(find "$work/site" -name index.html | wc -l)
[ "$pages" -ge 18 ] || fail "expected a page for each of the docs (18 or more), found $pages"
[ -f "$work/site/scenarios/index.html" ] || fail "expected scenarios/README.md in the site, found none"
[ -f "$work/site/search/search_index.json" ] || fail "expected the search index, found none"
loads=$(grep -rhoE '<(script|img)[^>]* src="https?://[^"]*"|<link[^>]* href="https?://[^"]*"' "$work/site" | sort -u || true)
[ -z "$loads" ] || fail "the site loads from the network: $loads"
echo "ok   - mkdocs build --strict: $pages pages, searchable, nothing loaded from the network"

# A copy of what the site is built from, broken one way at a time.
copy() {
  rm -rf "$work/tree"
  mkdir -p "$work/tree/scripts" "$work/tree/scenarios" "$work/tree/framework"
  cp -r "$source/docs" "$work/tree/docs"
  cp "$source/mkdocs.yml" "$work/tree/"
  cp "$source/scripts/mkdocs_hooks.py" "$work/tree/scripts/"
  cp "$source/scenarios/README.md" "$work/tree/scenarios/"
  cp "$source/framework/README.md" "$work/tree/framework/"
}
refused() {  # WHAT EXPECTED: the build of the broken copy must fail, naming EXPECTED
  if (cd "$work/tree" && mkdocs build --strict -d "$work/broken-site") >"$work/broken.log" 2>&1; then
    fail "mkdocs build --strict passed with $1"
  fi
  grep -q "$2" "$work/broken.log" || { cat "$work/broken.log" >&2; fail "with $1, expected a message naming $2"; }
  echo "ok   - refused: $1"
}
copy
echo "See [the missing page](no-such-page.md)." >>"$work/tree/docs/commands.md"
refused "a broken link" "no-such-page.md"
copy
printf '# Orphan\n\nNo page links here.\n' >"$work/tree/docs/orphan.md"
refused "a page no navigation entry reaches" "orphan.md"
copy
rm "$work/tree/docs/img/viewer-target.png"
refused "a missing picture" "viewer-target.png"
echo "docs_site_test: all passed"
