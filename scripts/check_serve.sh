#!/usr/bin/env bash
# Starts `mgrl serve` as a user would, fetches the page and three.js from it, then stops
# it with Ctrl-C (SIGINT) and checks that it said so and exited 0.
# Usage: scripts/check_serve.sh MGRL_BINARY SCENARIO [serve arguments...]
set -euo pipefail
mgrl="$1" scenario="$2"
shift 2
work="$(mktemp -d "${TMPDIR:-/tmp}/mgrl-check-serve.XXXXXX")"
pid=""
cleanup() {
  [ -n "$pid" ] && kill -KILL "$pid" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "check_serve: $*" >&2
  sed 's/^/  serve: /' "$work/err" >&2 || true
  exit 1
}
"$mgrl" serve "$scenario" --port 0 "$@" >"$work/out" 2>"$work/err" &
pid=$!
url=""
for _ in $(seq 1 600); do  # 60 s: the first start may build the graph
  url="$(grep -Eo 'http://127\.0\.0\.1:[0-9]+/' "$work/out" || true)"
  [ -n "$url" ] && break
  kill -0 "$pid" 2>/dev/null || fail "expected the server to keep running, found it exited"
  sleep 0.1
done
[ -n "$url" ] || fail "expected 'serving ... at http://127.0.0.1:PORT/' within 60 s, found none"
python3 - "$url" <<'PY' || fail "expected the page and three.js from $url"
import sys, urllib.request
url = sys.argv[1]
for path, kind in (("", "text/html"), ("node_modules/three/build/three.module.js", "text/javascript")):
    with urllib.request.urlopen(url + path, timeout=10) as r:
        assert r.status == 200 and r.headers["Content-Type"].startswith(kind), (path, r.status, r.headers["Content-Type"])
        assert len(r.read()) > 100, path
PY
kill -INT "$pid"
status=0
for _ in $(seq 1 100); do
  kill -0 "$pid" 2>/dev/null || break
  sleep 0.1
done
kill -0 "$pid" 2>/dev/null && fail "expected the server to stop within 10 s of Ctrl-C, found it running"
wait "$pid" || status=$?
pid=""
[ "$status" -eq 0 ] || fail "expected exit status 0 after Ctrl-C, found $status"
grep -q 'serve: stopped' "$work/err" || fail "expected 'serve: stopped' on stderr after Ctrl-C"
echo "check_serve: served the page and three.js at $url and stopped cleanly on Ctrl-C" >&2
