#!/usr/bin/env bash
# An installed mgrl, used from outside the repository: `cmake --install` into a temporary
# prefix; the installed headers resolve among themselves; the library example builds out
# of tree against find_package(mgrl) and lands hits; the installed mgrl trains the
# installed boxing scenario from another folder and serves its page with three.js.
# Usage: tests/install_test.sh BUILD_DIR SOURCE_DIR   (MGRL_CACHE: a cache to share)
set -euo pipefail
build="$(cd "$1" && pwd)"
source="$(cd "$2" && pwd)"
work="$(mktemp -d /tmp/mgrl-install-test.XXXXXX)"
server=""
cleanup() {
  if [ -n "$server" ]; then kill "$server" 2>/dev/null || true; fi
  rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "install_test: FAIL: $*" >&2
  exit 1
}
prefix="$work/prefix"

echo "# cmake --install $build --prefix $prefix"
cmake --install "$build" --prefix "$prefix" >"$work/install.log" 2>&1 ||
  { grep -v "^-- " "$work/install.log" >&2; fail "cmake --install"; }
for f in bin/mgrl lib/cmake/mgrl/mgrlConfig.cmake lib/cmake/mgrl/mgrlConfigVersion.cmake lib/cmake/mgrl/mgrlTargets.cmake \
         lib/libmgrl_session.a lib/libmgrl_builtins.a include/mgrl/session/session.hpp include/mgrl/builtin_plugins.hpp \
         share/mgrl/scenarios/boxing.yaml share/mgrl/web/index.html share/mgrl/web/viewer.js \
         share/mgrl/web/node_modules/three/build/three.module.js share/mgrl/web/node_modules/three/LICENSE; do
  [ -f "$prefix/$f" ] || fail "expected $f under the prefix, found none"
done
echo "ok   - the program, libraries, headers, package, scenarios and page are installed"

# Every "mgrl/..." an installed header includes is installed too.
missing=$(cd "$prefix/include" && grep -rhoE '#include "mgrl/[^"]+"' mgrl | sed -E 's/#include "(.*)"/\1/' | sort -u |
          while read -r h; do [ -f "$h" ] || echo "$h"; done)
[ -z "$missing" ] || fail "installed headers include headers that are not installed: $missing"
echo "ok   - every mgrl/ header an installed header includes is installed"

cd "$work"  # outside the repository from here on
if grep -q "^MGRL_PYTHON:BOOL=ON" "$build/CMakeCache.txt"; then
  env -u PYTHONPATH PYTHONPATH="$prefix/lib/python3/dist-packages" /usr/bin/python3 -c \
    "import mgrl, sys; assert mgrl.__file__.startswith(sys.argv[1]), mgrl.__file__; mgrl.scenario_path('boxing')" \
    "$prefix" || fail "the module installed in lib/python3/dist-packages does not import"
  echo "ok   - the Python module is installed in lib/python3/dist-packages and imports"
fi
"$prefix/bin/mgrl" --version | grep -q "mgrl" || fail "the installed mgrl --version printed no version"
echo "ok   - the installed mgrl runs: $("$prefix/bin/mgrl" --version)"

# The example as a user builds it: a copy of docs/examples, nothing else of the repository.
mkdir "$work/example-src"
cp "$source/docs/examples/CMakeLists.txt" "$source/docs/examples/session_example.cpp" "$work/example-src/"
cmake -S "$work/example-src" -B "$work/example" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
      -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF >"$work/configure.log" 2>&1 ||
  { cat "$work/configure.log" >&2; fail "configuring docs/examples against the installed package"; }
grep "^mgrl_DIR" "$work/example/CMakeCache.txt" | grep -q "$prefix" ||
  fail "find_package(mgrl) found another package than the one installed in $prefix"
cmake --build "$work/example" >"$work/build.log" 2>&1 || { tail -40 "$work/build.log" >&2; fail "building docs/examples"; }
echo "ok   - docs/examples builds out of tree with find_package(mgrl CONFIG)"
"$work/example/session_example" "$prefix/share/mgrl/scenarios/boxing.yaml" 10 >"$work/example.out" 2>"$work/example.err" ||
  { cat "$work/example.err" >&2; fail "session_example exited with an error"; }
grep -qE "^trained hit: [0-9]+ vertices" "$work/example.out" || fail "session_example trained no hit behaviour"
grep -qE "^[1-9][0-9]* hits in 10 s" "$work/example.out" || fail "session_example landed no hit: $(tail -1 "$work/example.out")"
echo "ok   - the example trains the installed boxing scenario and lands hits: $(tail -1 "$work/example.out")"

# The installed command line on the installed scenario, from this folder.
"$prefix/bin/mgrl" train "$prefix/share/mgrl/scenarios/boxing.yaml" --out "$work/policy" >"$work/train.out" 2>"$work/train.err" ||
  { tail -20 "$work/train.err" >&2; fail "mgrl train share/mgrl/scenarios/boxing.yaml"; }
[ -f "$work/policy/manifest.json" ] || fail "mgrl train wrote no policy bundle in $work/policy"
echo "ok   - the installed mgrl trains share/mgrl/scenarios/boxing.yaml from another folder"

# ...and serves the installed page (no MGRL_WEB, no --web): the page and three.js. A mark
# in the installed copy tells it from the repository's web/.
echo "<!-- the installed copy -->" >>"$prefix/share/mgrl/web/index.html"
env -u MGRL_WEB "$prefix/bin/mgrl" serve "$prefix/share/mgrl/scenarios/boxing.yaml" --policy "$work/policy" \
  --host 127.0.0.1 --port 0 >"$work/serve.out" 2>"$work/serve.err" &
server=$!
url=""
for _ in $(seq 1 600); do
  url=$(grep -oE "http://127\.0\.0\.1:[0-9]+/" "$work/serve.out" | head -1 || true)
  [ -n "$url" ] && break
  kill -0 "$server" 2>/dev/null || { cat "$work/serve.err" >&2; fail "mgrl serve exited before it listened"; }
  sleep 0.5
done
[ -n "$url" ] || fail "mgrl serve printed no http://127.0.0.1:PORT/ line within 300 s"
curl -sf "$url" | grep -q "the installed copy" || fail "mgrl serve served another page than share/mgrl/web's"
for path in "" viewer.js node_modules/three/build/three.module.js node_modules/three/build/three.core.js \
            node_modules/three/examples/jsm/controls/OrbitControls.js; do
  curl -sf -o "$work/fetched" "$url$path" || fail "the installed mgrl serve did not serve /$path"
done
grep -q "import" "$work/fetched" || fail "OrbitControls.js came back empty"
echo "ok   - the installed mgrl serve serves its page and three.js from share/mgrl/web"
echo "install_test: all passed"
