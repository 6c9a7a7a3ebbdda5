"""What the module carries wherever it is installed: its version (mgrl --version's), the
scenarios of the repository (listed, found by name, the same files), and clear refusals of
a scenario it does not have. Run by ctest (python_tests)."""
import os
import pathlib
import subprocess
import sys
import tempfile
import unittest

import mgrl

ROOT = pathlib.Path(os.environ.get("MGRL_SOURCE", pathlib.Path(__file__).resolve().parents[2]))
MGRL = os.environ.get("MGRL_BIN", str(ROOT / "build" / "app" / "mgrl"))


class PackageTest(unittest.TestCase):
    def test_the_version_is_the_command_lines(self):
        printed = subprocess.run([MGRL, "--version"], check=True, capture_output=True, text=True).stdout.split()
        self.assertEqual(printed, ["mgrl", mgrl.__version__])

    def test_the_scenarios_travel_with_the_module(self):
        shipped = mgrl.scenarios()
        self.assertEqual(shipped, sorted(p.name for p in (ROOT / "scenarios").glob("*.yaml")))
        self.assertIn("boxing.yaml", shipped)
        for name in shipped:
            path = pathlib.Path(mgrl.scenario_path(name))
            self.assertEqual(path.parent, pathlib.Path(mgrl.__file__).resolve().parent / "scenarios")
            self.assertEqual(path.read_bytes(), (ROOT / "scenarios" / name).read_bytes(), name)
        self.assertEqual(mgrl.scenario_path("boxing"), mgrl.scenario_path("boxing.yaml"))

    def test_a_session_opens_a_shipped_scenario_by_name_from_any_folder(self):
        cache = os.environ.get("MGRL_CACHE")
        here = os.getcwd()
        with tempfile.TemporaryDirectory(prefix="mgrl-package-") as empty:
            os.chdir(empty)
            try:
                for name in ("boxing", "boxing.yaml"):
                    s = mgrl.Session(name, cache=cache)
                    self.assertEqual(pathlib.Path(s.scenario), pathlib.Path(mgrl.scenario_path("boxing.yaml")))
                    self.assertEqual(s.behaviors, ["approach", "hit"])
                with self.assertRaises(mgrl.Error) as caught:
                    mgrl.Session("no_such_scenario", cache=cache)
                self.assertIn("no_such_scenario", str(caught.exception))
            finally:
                os.chdir(here)

    def test_a_scenario_it_does_not_have_is_refused_with_the_ones_it_has(self):
        with self.assertRaises(FileNotFoundError) as caught:
            mgrl.scenario_path("no_such_scenario")
        self.assertIn("boxing.yaml", str(caught.exception))
        self.assertIn("no_such_scenario.yaml", str(caught.exception))
        with self.assertRaises(ValueError) as caught:
            mgrl.scenario_path("scenarios/boxing.yaml")
        self.assertIn("a path", str(caught.exception))
        # A Session of a name that is neither a file here nor shipped says both.
        with self.assertRaisesRegex(mgrl.Error, r"scenario: expected a scenario file or the name of one the module "
                                                r"carries \(boxing, .*walk_to\), found 'no_such_scenario': no such "
                                                r"file in .* and no such name"):
            mgrl.Session("no_such_scenario")



class ImportTest(unittest.TestCase):
    """An import that cannot work says why, not "initialization failed"."""

    def run_python(self, *args, path):
        return subprocess.run([sys.executable, *args], capture_output=True, text=True, cwd=tempfile.mkdtemp(),
                              env={**os.environ, "PYTHONPATH": str(path)})

    def test_a_python_without_numpy_is_told_so(self):
        # -S: no site packages, so Debian's NumPy is out of reach, as in a bare pyenv or conda.
        package = pathlib.Path(mgrl.__file__).resolve().parent.parent
        run = self.run_python("-S", "-c", "import mgrl", path=package)
        self.assertNotEqual(run.returncode, 0)
        self.assertIn(f"mgrl: expected NumPy importable by this Python ({sys.executable}), found none", run.stderr)

    def test_a_core_built_for_another_python_is_told_so(self):
        copy = pathlib.Path(tempfile.mkdtemp()) / "mgrl"
        copy.mkdir()
        for source in pathlib.Path(mgrl.__file__).resolve().parent.glob("*.py"):
            (copy / source.name).write_bytes(source.read_bytes())
        (copy / "_core.cpython-399-x86_64-linux-gnu.so").write_bytes(b"")  # not this Python's
        run = self.run_python("-c", "import mgrl", path=copy.parent)
        self.assertNotEqual(run.returncode, 0)
        self.assertIn("mgrl: expected the C++ core built for this Python", run.stderr)
        self.assertIn("found _core.cpython-399-x86_64-linux-gnu.so", run.stderr)

if __name__ == "__main__":
    unittest.main()
