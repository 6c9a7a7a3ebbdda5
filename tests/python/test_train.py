"""Session.train trains as `mgrl train` does: the same table byte for byte from the same
scenario and settings, self-play rounds included, and a session left as it was opened.
Run by ctest (python_tests)."""
import json
import os
import pathlib
import subprocess
import tempfile
import unittest

import numpy as np

import mgrl
from test_problem import BOXING, SOURCE

MGRL = os.environ.get("MGRL_BIN", str(pathlib.Path(__file__).resolve().parents[2] / "build" / "app" / "mgrl"))
SPAR = SOURCE / "scenarios" / "spar_learned.yaml"
# A small sparring problem (8 positions, one opponent phase) in two self-play rounds.
SPAR_SETS = {"behaviors.spar.discretizer.sectors": 2, "behaviors.spar.discretizer.rings": 2,
             "behaviors.spar.discretizer.headings": 2, "behaviors.spar.environment.phases": 1,
             "behaviors.spar.environment.rounds": 2}
BOXING_SETS = {"behaviors.hit.learner.budget": 300000, "behaviors.approach.learner.budget": 300000}


def mgrl_train(scenario, sets, behavior, cache):
    """`mgrl train` on the command line: its bundle's folder and its --json report."""
    out = pathlib.Path(tempfile.mkdtemp(prefix="mgrl-python-train-")) / "policy"
    command = [MGRL, "train", str(scenario), "--behavior", behavior, "--out", str(out), "--json", "--cache", cache]
    for key, value in sets.items():
        command += ["--set", f"{key}={value}"]
    run = subprocess.run(command, capture_output=True, text=True, check=False)
    if run.returncode != 0:
        raise AssertionError(f"mgrl train failed ({run.returncode}): {run.stderr}")
    return out, json.loads(run.stdout)


class TrainTest(unittest.TestCase):
    def test_a_behaviour_trains_to_the_table_mgrl_train_writes(self):
        cache = tempfile.mkdtemp(prefix="mgrl-python-train-cache-")
        session = mgrl.Session(BOXING, cache=cache, sets=BOXING_SETS)
        mine = session.train("approach")
        out, report = mgrl_train(BOXING, BOXING_SETS, "approach", cache)
        theirs = np.load(out / "approach.q.npy")
        self.assertEqual(mine.dtype, np.float32)
        self.assertEqual(mine.shape, theirs.shape)
        self.assertEqual(mine.tobytes(), theirs.tobytes())
        self.assertEqual(session.last_train["updates"], report["behaviors"]["approach"]["updates"])
        self.assertEqual(session.last_train["learner"], report["behaviors"]["approach"]["learner"])

    def test_self_play_rounds_are_trained_as_mgrl_train_trains_them(self):
        cache = tempfile.mkdtemp(prefix="mgrl-python-spar-cache-")
        session = mgrl.Session(SPAR, cache=cache, sets=SPAR_SETS)
        mine = session.train("spar")
        rounds = session.last_train["rounds"]
        self.assertEqual([r["round"] for r in rounds], [1, 2])
        self.assertEqual(rounds[1]["opponent"], "round 1")
        out, report = mgrl_train(SPAR, SPAR_SETS, "spar", cache)
        self.assertEqual(len(report["behaviors"]["spar"]["rounds"]), 2)
        # The last round's table under the behaviour's name, round 1's beside it.
        self.assertEqual(mine.tobytes(), np.load(out / "spar.q.npy").tobytes())
        first = np.load(out / "spar-round1.q.npy")
        self.assertNotEqual(mine.tobytes(), first.tobytes())
        # The session still plays the scenario's opponent: training again gives the same table.
        again = session.train("spar")
        self.assertEqual(again.tobytes(), mine.tobytes())


if __name__ == "__main__":
    unittest.main()
