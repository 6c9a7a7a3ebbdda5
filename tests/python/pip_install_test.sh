#!/usr/bin/env bash
# pip install . as a Python user does it, offline, into a fresh venv that sees Debian's NumPy
# and Jupyter (--system-site-packages): the module imports from outside the repository with
# its version, metadata and type stubs, finds its scenarios, plays a saved policy from an
# empty folder without training, runs a notebook copied elsewhere, and pip uninstall
# removes it.
# Usage: tests/python/pip_install_test.sh BUILD_DIR SOURCE_DIR
#   (MGRL_BUILD_DIR=BUILD_DIR: pip builds the module in that build, nothing compiles again)
set -euo pipefail
build="$(cd "$1" && pwd)"
source="$(cd "$2" && pwd)"
work="$(mktemp -d /tmp/mgrl-pip-test.XXXXXX)"
trap 'rm -rf "$work"' EXIT
fail() {
  echo "pip_install_test: FAIL: $*" >&2
  exit 1
}
version=$(sed -nE 's/^project\(mgrl VERSION ([0-9.]+).*/\1/p' "$source/CMakeLists.txt")

/usr/bin/python3 -m venv --system-site-packages "$work/venv"
py="$work/venv/bin/python"
echo "# pip install --no-index --no-build-isolation $source (venv $work/venv)"
before=$(grep "^Python_EXECUTABLE" "$build/CMakeCache.txt" || true)
MGRL_BUILD_DIR="$build" "$py" -m pip install --no-index --no-build-isolation "$source" >"$work/pip.log" 2>&1 ||
  { tail -30 "$work/pip.log" >&2; fail "pip install ."; }
[ "$(grep "^Python_EXECUTABLE" "$build/CMakeCache.txt" || true)" = "$before" ] ||
  fail "pip install . changed the build folder's Python ($before) to $(grep "^Python_EXECUTABLE" "$build/CMakeCache.txt")"
"$py" -m pip show mgrl >"$work/show.txt" || fail "pip show mgrl"
grep -qx "Version: $version" "$work/show.txt" || fail "pip show mgrl: expected Version: $version, found $(grep Version "$work/show.txt")"
grep -q "^Requires: numpy" "$work/show.txt" || fail "pip show mgrl: expected Requires: numpy"
echo "ok   - pip install . into a venv, offline: mgrl $version"

cd "$work"  # outside the repository from here on
env -u PYTHONPATH -u MGRL_SOURCE "$py" - "$work/venv" "$version" <<'PY' || fail "import mgrl from the venv"
import pathlib, sys
import mgrl
venv, version = pathlib.Path(sys.argv[1]), sys.argv[2]
where = pathlib.Path(mgrl.__file__).resolve()
assert venv in where.parents, f"expected mgrl from {venv}, found {where}"
assert mgrl.__version__ == version, f"expected __version__ {version}, found {mgrl.__version__}"
scenario = pathlib.Path(mgrl.scenario_path("boxing.yaml"))
assert venv in scenario.parents and scenario.is_file(), f"expected boxing.yaml in the venv, found {scenario}"
for typed in ("__init__.pyi", "env.pyi", "compare.pyi", "py.typed"):
    assert (where.parent / typed).is_file(), f"expected the type stubs' {typed} installed beside the module"
s = mgrl.Session("boxing")
print(f"ok   - import mgrl from {where.parent}, version {mgrl.__version__}, {s.problem('approach').rewards.shape} approach problem")
# A policy saved here, for the next process to play.
q = s.train("approach", learner="value_iteration")
h = s.train("hit", sets={"budget": 300000})
s.save_policy("saved-policy", {"approach": q, "hit": h})
PY
# From an empty folder, a saved policy plays without anything trained.
env -u PYTHONPATH -u MGRL_SOURCE "$py" - "$work/saved-policy" >"$work/policy.log" 2>&1 <<'PY' ||
import mgrl, sys
r = mgrl.Session("boxing", policy=sys.argv[1]).evaluate(trials=20, seed=1)
print("success", r["success_rate"])
PY
  { cat "$work/policy.log" >&2; fail "evaluate with a saved policy"; }
if grep -q "train" "$work/policy.log"; then cat "$work/policy.log" >&2; fail "evaluate with a saved policy trained something"; fi
echo "ok   - from an empty folder, Session(\"boxing\", policy=...) evaluates a saved policy without training ($(grep success "$work/policy.log"))"

# A notebook copied out of the repository runs with the installed module: the one that
# uses most of it (a session, training, comparing, the tables as NumPy). Every notebook runs
# from the repository in python_notebooks; running all three here too cost about a minute
# of the test command.
# The venv's own Jupyter kernel (the system's python3 kernel would run /usr/bin/python3).
"$py" -m ipykernel install --sys-prefix --name mgrl-venv >/dev/null 2>&1 || fail "a Jupyter kernel for the venv"
mkdir "$work/notebooks"
cp "$source/notebooks/2_compare_a_python_learner.ipynb" "$work/notebooks/"
for notebook in "$work"/notebooks/*.ipynb; do
  name="$(basename "$notebook")"
  env -u PYTHONPATH -u MGRL_SOURCE -u MPLBACKEND MGRL_NOTEBOOK_QUICK=1 PYDEVD_DISABLE_FILE_VALIDATION=1 \
    "$py" -m nbconvert --to notebook --execute --ExecutePreprocessor.timeout=900 \
    --ExecutePreprocessor.kernel_name=mgrl-venv --output-dir "$work/out" "$notebook" \
    >"$work/nb.log" 2>&1 || { tail -30 "$work/nb.log" >&2; fail "$name failed with the installed module"; }
  "$py" - "$work/out/$name" <<'PY' || fail "$name's output"
import json, sys
cells = json.load(open(sys.argv[1]))["cells"]
outputs = [o for c in cells if c["cell_type"] == "code" for o in c.get("outputs", [])]
assert not [o for o in outputs if o["output_type"] == "error"], "a cell raised an error"
assert any("image/png" in o.get("data", {}) for o in outputs), "no figure drawn"
PY
  echo "ok   - $name runs from outside the repository with the installed module"
done

"$py" -m pip uninstall -y mgrl >"$work/uninstall.log" 2>&1 || fail "pip uninstall -y mgrl"
if env -u PYTHONPATH "$py" -c "import mgrl" 2>/dev/null; then fail "import mgrl still works after pip uninstall"; fi
[ -z "$(find "$work/venv" -path '*site-packages/mgrl*' -print -quit)" ] || fail "pip uninstall left files of mgrl in the venv"
echo "ok   - pip uninstall mgrl removes it"

# A build folder configured without the module is refused, saying so, and nothing is installed.
mkdir "$work/no-module-build"
echo "MGRL_PYTHON:BOOL=OFF" >"$work/no-module-build/CMakeCache.txt"
if MGRL_BUILD_DIR="$work/no-module-build" "$py" -m pip install --no-index --no-build-isolation "$source" \
  >"$work/refused.log" 2>&1; then
  fail "pip install . built from a folder configured without the Python module"
fi
grep -q "configured with the Python module (MGRL_PYTHON=ON), found it without" "$work/refused.log" ||
  { tail -20 "$work/refused.log" >&2; fail "the refusal does not say what was expected"; }
if env -u PYTHONPATH "$py" -c "import mgrl" 2>/dev/null; then fail "a refused install left mgrl importable"; fi
echo "ok   - a build folder without the Python module is refused with what was expected"
echo "pip_install_test: all passed"
