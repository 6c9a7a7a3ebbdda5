"""The type stubs (python/mgrl/*.pyi) and the docstrings they are made from: the stubs are
valid Python, name every public member, and scripts/python_stubs.py refuses a member
whose docstring lacks what a stub needs. (Drift between the stubs and the module is ctest's
python_stubs.) Run by ctest (python_tests)."""
import ast
import importlib.util
import unittest

import mgrl
from test_problem import SOURCE

spec = importlib.util.spec_from_file_location("python_stubs", SOURCE / "scripts" / "python_stubs.py")
python_stubs = importlib.util.module_from_spec(spec)
spec.loader.exec_module(python_stubs)


class StubsTest(unittest.TestCase):
    def test_the_stubs_are_python_and_name_every_public_member(self):
        folder = SOURCE / "python" / "mgrl"
        self.assertTrue((folder / "py.typed").exists())
        trees = {name: ast.parse((folder / name).read_text()) for name in ("__init__.pyi", "env.pyi", "compare.pyi")}
        top = {n.name for n in trees["__init__.pyi"].body if isinstance(n, (ast.ClassDef, ast.FunctionDef))}
        top |= {a.asname for n in trees["__init__.pyi"].body if isinstance(n, ast.ImportFrom) for a in n.names}
        self.assertEqual(set(mgrl.__all__) | {"inspect"}, top - {None})
        session = next(n for n in trees["__init__.pyi"].body if isinstance(n, ast.ClassDef) and n.name == "Session")
        evaluate = next(n for n in session.body if isinstance(n, ast.FunctionDef) and n.name == "evaluate")
        self.assertEqual(ast.unparse(evaluate.returns), "dict[str, typing.Any]")
        self.assertIn("train_missing", [a.arg for a in evaluate.args.args])

    def test_help_says_what_each_member_does_its_arguments_and_its_return(self):
        for member in (mgrl.Session.evaluate, mgrl.Session.train, mgrl.MotionGraphEnv.step,
                       mgrl.MotionGraphVectorEnv.reset, mgrl.load_policy, mgrl.compare):
            with self.subTest(member=member.__qualname__):
                doc = member.__doc__
                self.assertIn("Parameters\n", doc)
                self.assertIn("Returns\n", doc)
        self.assertIn("Returns", mgrl.Problem.rewards.__doc__)
        self.assertIn("Parameters", mgrl.Session.__doc__)

    def test_a_member_without_what_its_stub_needs_is_refused(self):
        def undocumented(x):
            return x

        def unlisted(x, y=1):
            """Adds.

            Parameters
            ----------
            x : int
                One.

            Returns
            -------
            int
            """

        def not_a_type(x):
            """Adds.

            Parameters
            ----------
            x : an int, positive
                One.

            Returns
            -------
            int
            """

        def no_return(x):
            """Adds.

            Parameters
            ----------
            x : int
                One.
            """

        cases = [(undocumented, r"f: expected a docstring saying what it does, found none"),
                 (unlisted, r"f: expected its parameter 'y' under Parameters as 'y : type', found no entry"),
                 (not_a_type, r"f, parameter x: expected a Python type expression, found 'an int, positive'"),
                 (no_return, r"f: expected a Returns section with a type, found none")]
        for function, message in cases:
            with self.subTest(function=function.__name__):
                with self.assertRaisesRegex(python_stubs.Refused, message):
                    python_stubs.function_stub("f", function, "f")

        def identity(x, scale=2.0):
            """The value.

            Parameters
            ----------
            x : int
                One.
            scale : float
                Unused.

            Returns
            -------
            int
            """

        self.assertEqual(python_stubs.function_stub("f", identity, "f"), "def f(x: int, scale: float = 2.0) -> int: ...")


if __name__ == "__main__":
    unittest.main()
