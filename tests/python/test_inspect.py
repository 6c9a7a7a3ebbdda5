"""mgrl.inspect (the capture report is a library call of the motion stage): the
same report as `mgrl inspect --json`, one path or several, and one clear mgrl.Error for a
malformed file. Run by ctest (python_tests)."""
import json
import os
import pathlib
import subprocess
import unittest

import mgrl

ROOT = pathlib.Path(os.environ.get("MGRL_SOURCE", pathlib.Path(__file__).resolve().parents[2]))
DATA = ROOT / "tests" / "data"
MGRL = os.environ.get("MGRL_BIN", str(ROOT / "build" / "app" / "mgrl"))


class InspectTest(unittest.TestCase):
    def test_the_report_is_mgrl_inspect_json(self):
        files = [DATA / "boxer21.bvh", DATA / "kick.bvh"]
        with self.assertWarns(UserWarning) as warned:  # the loader's warnings, as Python's
            mine = mgrl.inspect(files)
        self.assertIn("no fist joint", str(warned.warning))
        cli = json.loads(subprocess.run([MGRL, "inspect", *map(str, files), "--json"], check=True,
                                        capture_output=True, text=True).stdout)
        self.assertEqual(mine, cli)
        self.assertEqual([pathlib.Path(f["path"]).name for f in mine["files"]], ["boxer21.bvh", "kick.bvh"])
        self.assertGreater(mine["files"][0]["joints"], 1)

    def test_one_path_alone(self):
        one = mgrl.inspect(DATA / "tiny.bvh")
        self.assertEqual(len(one["files"]), 1)
        self.assertEqual(one["files"][0]["frames"], mgrl.inspect([str(DATA / "tiny.bvh")])["files"][0]["frames"])

    def test_a_malformed_file_is_one_clear_error(self):
        with self.assertRaises(mgrl.Error) as caught:
            mgrl.inspect([DATA / "tiny.bvh", DATA / "truncated.bvh"])
        self.assertIn("truncated.bvh", str(caught.exception))
        with self.assertRaises(mgrl.Error):
            mgrl.inspect(DATA / "no_such_file.bvh")


if __name__ == "__main__":
    unittest.main()
