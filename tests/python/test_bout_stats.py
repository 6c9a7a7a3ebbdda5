"""mgrl.bout_stats (the bout report is a library call): the same report as
`mgrl stats --json`, a comparison of two groups, and one clear error for a bout that is
not there. Run by ctest (python_tests)."""
import json
import os
import pathlib
import subprocess
import unittest

import mgrl

ROOT = pathlib.Path(os.environ.get("MGRL_SOURCE", pathlib.Path(__file__).resolve().parents[2]))
STATS = ROOT / "tests" / "data" / "stats"
MGRL = os.environ.get("MGRL_BIN", str(ROOT / "build" / "app" / "mgrl"))


class BoutStatsTest(unittest.TestCase):
    def test_the_report_is_mgrl_stats_json(self):
        mine = mgrl.bout_stats([STATS / "stand", STATS / "punch_far"])
        cli = json.loads(subprocess.run([MGRL, "stats", str(STATS / "stand"), str(STATS / "punch_far"), "--json"],
                                        check=True, capture_output=True, text=True).stdout)
        self.assertEqual(mine, cli)
        self.assertEqual([b["name"] for b in mine["bouts"]], ["stand", "punch_far"])
        self.assertEqual(mine["pooled"]["bouts"], 2)
        # stand/: the fighters 1.0 m apart; punch_far/: about 3 m (tests/data/stats/README.md).
        self.assertAlmostEqual(mine["bouts"][0]["distance_m"]["median"], 1.0, places=2)
        self.assertGreater(mine["bouts"][1]["distance_m"]["median"], 2.5)

    def test_two_groups_compared(self):
        report = mgrl.bout_stats([STATS / "punch_near"], against=[STATS / "punch_far"])
        self.assertEqual(set(report), {"params", "real", "synthetic", "wasserstein1"})
        self.assertGreater(report["wasserstein1"]["distance_m"], 0)

    def test_a_missing_bout_is_one_clear_error(self):
        with self.assertRaises(mgrl.Error) as caught:
            mgrl.bout_stats([STATS / "no_such_bout"])
        self.assertIn("no_such_bout", str(caught.exception))
        self.assertIn("expected a folder of BVH files", str(caught.exception))
        with self.assertRaises(TypeError):
            mgrl.bout_stats(str(STATS / "punch_near"))


if __name__ == "__main__":
    unittest.main()
