"""Executes every notebook in notebooks/ with Debian's Jupyter (nbconvert --execute, the
kernel of /usr/bin/python3) as CI does, in quick mode (MGRL_NOTEBOOK_QUICK=1: smaller
training budgets), and checks that each ran without an error and drew its figures.
Usage: python3 tests/python/notebooks_check.py [NOTEBOOK...]   (ctest: python_notebooks)"""
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

SOURCE = pathlib.Path(os.environ.get("MGRL_SOURCE", pathlib.Path(__file__).resolve().parents[2]))


def main(argv):
    notebooks = [pathlib.Path(a).resolve() for a in argv] or sorted((SOURCE / "notebooks").glob("*.ipynb"))
    if not notebooks:
        print(f"notebooks_check: expected notebooks in {SOURCE / 'notebooks'}, found none", file=sys.stderr)
        return 1
    probe = subprocess.run([sys.executable, "-c", "import nbconvert, ipykernel, matplotlib"], capture_output=True,
                           text=True)
    if probe.returncode != 0:
        print("notebooks_check: expected Jupyter's nbconvert, ipykernel and matplotlib for "
              f"{sys.executable}, found: {probe.stderr.strip().splitlines()[-1]} (run scripts/setup.sh --python)",
              file=sys.stderr)
        return 1
    env = dict(os.environ, MGRL_NOTEBOOK_QUICK="1", MGRL_SOURCE=str(SOURCE),
               PYDEVD_DISABLE_FILE_VALIDATION="1")
    env.pop("MPLBACKEND", None)  # the notebooks draw with Jupyter's inline backend
    failed = 0
    with tempfile.TemporaryDirectory(prefix="mgrl-notebooks-") as out:
        env.setdefault("MGRL_CACHE", os.path.join(out, "cache"))
        for notebook in notebooks:
            started = time.monotonic()
            run = subprocess.run([sys.executable, "-m", "nbconvert", "--to", "notebook", "--execute",
                                  "--ExecutePreprocessor.timeout=900", "--ExecutePreprocessor.kernel_name=python3",
                                  "--output-dir", out, str(notebook)],
                                 cwd=notebook.parent, env=env, capture_output=True, text=True)
            seconds = time.monotonic() - started
            if run.returncode != 0:
                failed += 1
                print(f"{notebook.name}: FAILED after {seconds:.0f} s\n{run.stderr[-3000:]}", file=sys.stderr)
                continue
            executed = json.loads((pathlib.Path(out) / notebook.name).read_text())
            errors = [o for c in executed["cells"] if c["cell_type"] == "code" for o in c.get("outputs", [])
                      if o.get("output_type") == "error"]
            images = sum("image/png" in o.get("data", {}) for c in executed["cells"] if c["cell_type"] == "code"
                         for o in c.get("outputs", []))
            unrun = [c for c in executed["cells"] if c["cell_type"] == "code" and c.get("execution_count") is None]
            if errors or unrun or images == 0:
                failed += 1
                print(f"{notebook.name}: expected every cell run without an error and at least one figure, found "
                      f"{len(errors)} errors, {len(unrun)} cells not run, {images} figures", file=sys.stderr)
                continue
            print(f"{notebook.name}: ran in {seconds:.0f} s, {images} figures")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
