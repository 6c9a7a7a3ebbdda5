#!/usr/bin/env bash
# The Debian package, as a user gets it: cpack -G DEB in the build folder; its contents
# (dpkg-deb -c) hold the program, the module for Debian's Python, the share folder and the
# CMake package; its control file declares what it needs; extracted (dpkg-deb -x), its mgrl
# runs and its module imports.
# Usage: tests/package_test.sh BUILD_DIR
set -euo pipefail
build="$(cd "$1" && pwd)"
work="$(mktemp -d /tmp/mgrl-package-test.XXXXXX)"
trap 'rm -rf "$work"' EXIT
fail() {
  echo "package_test: FAIL: $*" >&2
  exit 1
}
for tool in cpack dpkg-deb dpkg-shlibdeps; do
  command -v "$tool" >/dev/null || fail "expected $tool (cmake, dpkg-dev: scripts/setup.sh installs them), found none"
done
echo "# cpack -G DEB -B $work"
(cd "$build" && cpack -G DEB -B "$work" >"$work/cpack.log" 2>&1) || { tail -30 "$work/cpack.log" >&2; fail "cpack -G DEB"; }
deb=$(find "$work" -maxdepth 1 -name 'mgrl_*.deb' | head -1)
[ -n "$deb" ] || fail "cpack wrote no mgrl_*.deb in $work"
echo "ok   - cpack -G DEB wrote $(basename "$deb") ($(du -h "$deb" | cut -f1))"

dpkg-deb -c "$deb" | awk '{print $NF}' >"$work/contents"
for f in ./usr/bin/mgrl ./usr/share/mgrl/scenarios/boxing.yaml ./usr/share/mgrl/web/index.html \
         ./usr/share/mgrl/web/node_modules/three/build/three.module.js ./usr/lib/python3/dist-packages/mgrl/__init__.py \
         ./usr/lib/python3/dist-packages/mgrl/scenarios/boxing.yaml ./usr/include/mgrl/session/session.hpp; do
  grep -qx "$f" "$work/contents" || fail "expected $f in the package, found it missing"
done
grep -qE '^\./usr/lib/python3/dist-packages/mgrl/_core\..*\.so$' "$work/contents" ||
  fail "expected the module's _core*.so in /usr/lib/python3/dist-packages/mgrl"
grep -qE '^\./usr/lib/.*cmake/mgrl/mgrlConfig\.cmake$' "$work/contents" || fail "expected the CMake package's mgrlConfig.cmake"
echo "ok   - it holds mgrl, the module for Debian's Python, share/mgrl and the CMake package"

dpkg-deb -f "$deb" Depends >"$work/depends"
for need in python3-numpy libyaml-cpp libfmt; do
  grep -q "$need" "$work/depends" || fail "expected Depends to name $need, found: $(cat "$work/depends")"
done
echo "ok   - Depends: $(cat "$work/depends")"

dpkg-deb -x "$deb" "$work/root"
cd "$work"
"$work/root/usr/bin/mgrl" --version | grep -q "^mgrl " || fail "the extracted mgrl --version printed no version"
env -u PYTHONPATH PYTHONPATH="$work/root/usr/lib/python3/dist-packages" /usr/bin/python3 -c \
  "import mgrl, sys; assert mgrl.__file__.startswith(sys.argv[1]), mgrl.__file__; print(mgrl.__version__)" \
  "$work/root" >/dev/null || fail "the extracted module does not import"
echo "ok   - the extracted mgrl runs ($("$work/root/usr/bin/mgrl" --version)) and its module imports"
echo "package_test: all passed"
