#!/usr/bin/env python3
"""The README check's comparison (scripts/readme_outputs.py): a changed deterministic
figure fails it, a changed timing does not. ctest runs this as `readme_outputs_rules`; the
check itself runs on the real README in scripts/test.sh."""
import os
import sys
import unittest

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts"))
import readme_outputs as r  # noqa: E402

EVAL = ("controller policy: 300 trials, success rate 100.0 %, time to hit mean 3.40 s median 3.38 s, "
        "mean return 0.421, 7.47 Mdecisions/s")
TRAIN = "  hit        q_learning           20000000 updates     10.20 s     1.96 Mupdates/s  residual 0.574  table 11.0 MB"
SIMULATE = "simulate (policy controller, sparring): 30 avatars x 999 frames (33.3 s) in 3.5 ms: 8.66 Mavatar-frames/s"


class SampleLines(unittest.TestCase):
    def test_the_same_line_agrees(self):
        for line in (EVAL, TRAIN, SIMULATE):
            self.assertIsNone(r.compare_lines(line, line))

    def test_timings_and_rates_are_not_compared(self):
        self.assertIsNone(r.compare_lines(EVAL, EVAL.replace("7.47 Mdecisions/s", "463.0 kdecisions/s")))
        self.assertIsNone(r.compare_lines(TRAIN, TRAIN.replace("10.20 s", "31.07 s").replace("1.96 M", "612.3 k")))
        self.assertIsNone(r.compare_lines(SIMULATE, SIMULATE.replace("3.5 ms", "12.0 ms")))
        slower = SIMULATE.replace("in 3.5 ms: 8.66 Mavatar-frames/s", "in 0.10 s: 294.4 kavatar-frames/s")
        self.assertIsNone(r.compare_lines(SIMULATE, slower))  # another unit on a slower machine
        build = "build           0.006 s (reused from ~/.cache/mgrl/graphs/boxing-ef73e760)"
        self.assertIsNone(r.compare_lines(build, "build           1.250 s (reused from ~/.cache/mgrl/graphs/boxing-0123abcd)"))

    def test_a_changed_deterministic_figure_fails(self):
        self.assertIn("100.0 (now 95.0)", r.compare_lines(EVAL, EVAL.replace("success rate 100.0", "success rate 95.0")))
        self.assertIn("3.40 (now 4.2)", r.compare_lines(EVAL, EVAL.replace("mean 3.40 s", "mean 4.2 s")))
        self.assertIn("0.574", r.compare_lines(TRAIN, TRAIN.replace("residual 0.574", "residual 0.61")))
        self.assertIn("11.0", r.compare_lines(TRAIN, TRAIN.replace("table 11.0 MB", "table 12.5 MB")))
        self.assertIn("999", r.compare_lines(SIMULATE, SIMULATE.replace("999 frames", "900 frames")))
        self.assertEqual(r.compare_lines("hits: 605 (36.3 per avatar-minute)", "hits: 605 (36.3 per minute)"),
                         "the words differ")

    def test_the_tolerance_is_one_percent_or_a_unit_of_the_last_digit(self):
        self.assertIsNone(r.compare_lines("hits: 605", "hits: 611"))  # 1 %
        self.assertIsNotNone(r.compare_lines("hits: 605", "hits: 612"))
        self.assertIsNone(r.compare_lines("states 117", "states 118"))  # one unit
        self.assertIsNotNone(r.compare_lines("states 117", "states 119"))
        self.assertIsNone(r.compare_lines("rate 5.0 %", "rate 5.1 %"))
        self.assertIsNotNone(r.compare_lines("rate 5.0 %", "rate 5.3 %"))


class Figures(unittest.TestCase):
    OUTPUT = [EVAL, "random baseline on the same starts: success rate 5.0 %, time to hit mean 5.64 s"]

    def test_a_figure_found_within_tolerance(self):
        self.assertIsNone(r.find_figure("success rate 100.0 %, time to hit mean 3.40 s", self.OUTPUT))
        self.assertIsNone(r.find_figure("success rate 5.0 %", self.OUTPUT))
        self.assertIsNone(r.find_figure("success rate 99..100 %", self.OUTPUT))

    def test_a_wrong_figure_fails_saying_what_was_found(self):
        self.assertEqual(r.find_figure("success rate 95.0 %", self.OUTPUT),
                         "found success rate 100.0 % / success rate 5.0 %")
        self.assertIsNotNone(r.find_figure("success rate 100.0 %, time to hit mean 4.2 s", self.OUTPUT))
        self.assertIsNotNone(r.find_figure("success rate 93..96 %", self.OUTPUT))
        self.assertEqual(r.find_figure("hit rate 100.0 %", self.OUTPUT), "found no line with those words")


class WhereMarkersAreRead(unittest.TestCase):
    def test_the_readme_every_docs_page_and_the_scenario_keys_are_read(self):
        read = [os.path.relpath(p, r.ROOT) for p in r.documents()]
        self.assertEqual(read[0], "README.md")
        self.assertIn(os.path.join("scenarios", "README.md"), read)
        docs = sorted(f for f in os.listdir(os.path.join(r.ROOT, "docs")) if f.endswith(".md"))
        self.assertEqual([p for p in read if p.startswith("docs")], [os.path.join("docs", f) for f in docs])

    def test_a_marker_in_a_page_is_found_and_named_by_its_file(self):
        lines = ["text", "<!-- mgrl-figure: eval scenarios/boxing.yaml => success rate 100.0 % -->"]
        self.assertEqual(r.figures(lines, "docs/commands.md"), [(1, ["eval scenarios/boxing.yaml"], ["success rate 100.0 %"])])
        with self.assertRaises(SystemExit) as failed:
            r.figures(["<!-- mgrl-figure: eval scenarios/boxing.yaml -->"], "docs/commands.md")
        self.assertIn("docs/commands.md:1:", str(failed.exception))


class Pages(unittest.TestCase):
    """The docs' pages are reachable and their links lead somewhere."""

    LINK = __import__("re").compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")

    def test_the_index_links_every_page(self):
        docs = os.path.join(r.ROOT, "docs")
        index = open(os.path.join(docs, "index.md")).read()
        linked = set(self.LINK.findall(index))
        pages = sorted(f for f in os.listdir(docs) if f.endswith(".md") and f != "index.md")
        self.assertEqual([p for p in pages if p not in linked], [], "pages docs/index.md does not link")

    def test_every_relative_link_in_the_readme_and_docs_resolves(self):
        broken = []
        for path in r.documents():
            text = open(path).read()
            for target in self.LINK.findall(text):
                if "://" in target or target.startswith("mailto:"):
                    continue
                if not os.path.exists(os.path.normpath(os.path.join(os.path.dirname(path), target))):
                    broken.append(f"{os.path.relpath(path, r.ROOT)}: {target}")
        self.assertEqual(broken, [])


if __name__ == "__main__":
    unittest.main()
