#!/usr/bin/env python3
"""The mgrl module's type stubs (python/mgrl/*.pyi), made from the module itself.

Each public member's stub comes from what the module says about it: the names, kinds and
defaults of its parameters (Python's signature, or the signature line pybind11 puts first
in a C++ member's docstring) and their types from its docstring, written in the NumPy
convention ("name : type" under Parameters, the type under Returns, "name : type" under
Attributes), where each type is a Python type expression. A member without a docstring,
a parameter without its entry, an entry for no parameter or a type that is not a Python
expression is refused, so help() of every public member says what it does, its arguments
and its return.

Usage: PYTHONPATH=build/python python3 scripts/python_stubs.py [--check] [FOLDER]
  writes FOLDER/__init__.pyi, env.pyi and compare.pyi (FOLDER: python/mgrl); with
  --check writes nothing and fails, showing the difference, when FOLDER's stubs are not
  what the module gives (the CI's drift check).
"""
import argparse
import ast
import difflib
import enum
import inspect
import pathlib
import re
import sys
import types

ROOT = pathlib.Path(__file__).resolve().parents[1]
SECTION = re.compile(r"^(\w[\w ]*)\n-{3,}$", re.M)
PYBIND_SIGNATURE = re.compile(r"^(\w+)\((.*)\)(?: -> (.+))?$")
# Members of every class that the stubs leave out (Python's own) and dunders they keep.
KEPT_DUNDERS = ("__init__", "__enter__", "__exit__", "__getitem__", "__contains__")
HEADER = ("# The mgrl module's type stubs, made by scripts/python_stubs.py from the module's own\n"
          "# signatures and docstrings; CI fails when they differ from what it gives.\n")


class Refused(Exception):
    pass


def sections(doc):
    """A NumPy docstring's summary and its sections, {title: text}."""
    doc = inspect.cleandoc(doc or "")
    parts = SECTION.split(doc)
    out = {"": parts[0].strip()}
    for title, text in zip(parts[1::2], parts[2::2]):
        out[title.strip()] = text.strip("\n")
    return out


def entries(text):
    """A section's "name : type" (or bare "type") entries, {name: type}, in order."""
    out = {}
    for line in (text or "").splitlines():
        if not line or line[0].isspace():
            continue
        name, sep, kind = line.partition(" : ")
        out[name.strip()] = kind.strip() if sep else None
    return out


def returned(text, where):
    """The type a Returns section gives: its first unindented line, "name : type" or "type"."""
    for line in (text or "").splitlines():
        if line and not line[0].isspace():
            name, sep, kind = line.partition(" : ")
            return checked(kind if sep else name, where)
    raise Refused(f"{where}: expected a Returns section with a type, found none")


def checked(kind, where):
    kind = kind.strip()
    try:
        ast.parse(kind, mode="eval")
    except SyntaxError:
        raise Refused(f"{where}: expected a Python type expression, found {kind!r}") from None
    return kind


def default_text(value):
    if value is None or isinstance(value, (bool, int, float, str)):
        return repr(value)
    if isinstance(value, tuple) and all(isinstance(v, (bool, int, float, str)) for v in value):
        return repr(value)
    return "..."


def pybind_parameters(doc, where):
    """(name, default text or None) of each parameter in pybind11's signature line."""
    first = (doc or "").splitlines()[0] if doc else ""
    match = PYBIND_SIGNATURE.match(first)
    if not match:
        raise Refused(f"{where}: expected pybind11's signature line, found {first!r}")
    tree = ast.parse(f"def f({match.group(2)}): pass").body[0].args
    names = [a.arg for a in tree.args]
    defaults = [None] * (len(names) - len(tree.defaults)) + [ast.unparse(d) for d in tree.defaults]
    return list(zip(names, defaults))


def python_parameters(function):
    out = []
    for p in inspect.signature(function).parameters.values():
        text = None if p.default is inspect.Parameter.empty else default_text(p.default)
        prefix = {inspect.Parameter.VAR_POSITIONAL: "*", inspect.Parameter.VAR_KEYWORD: "**"}.get(p.kind, "")
        out.append((prefix + p.name, text, p.kind))
    return out


def function_stub(name, function, where, indent="", doc=None, method=False):
    """`def name(...) -> type: ...` from the function's parameters and (its own, or the
    class's for __init__) docstring."""
    own = sections(function.__doc__ if doc is None else doc)
    is_pybind = isinstance(function, types.BuiltinFunctionType) or type(function).__name__ == "instancemethod"
    if not own[""] and doc is None:
        raise Refused(f"{where}: expected a docstring saying what it does, found none")
    if is_pybind:
        parameters = [(n, d, inspect.Parameter.POSITIONAL_OR_KEYWORD) for n, d in pybind_parameters(function.__doc__,
                                                                                                     where)]
        if doc is None:  # the signature line is pybind11's, the text after it ours
            own = sections(function.__doc__.split("\n", 1)[1] if "\n" in function.__doc__ else "")
            if not own[""]:
                raise Refused(f"{where}: expected a docstring after pybind11's signature line, found none")
    else:
        parameters = python_parameters(function)
    documented = entries(own.get("Parameters"))
    text, keyword_only = [], False
    for i, (pname, default, kind) in enumerate(parameters):
        bare = pname.lstrip("*")
        if method and i == 0:
            text.append(bare)
            continue
        if kind == inspect.Parameter.KEYWORD_ONLY and not keyword_only:
            text.append("*")
            keyword_only = True
        if bare not in documented or documented[bare] is None:
            raise Refused(f"{where}: expected its parameter '{bare}' under Parameters as '{bare} : type', found "
                          f"{'no entry' if bare not in documented else 'no type'}")
        annotation = checked(documented.pop(bare), f"{where}, parameter {bare}")
        text.append(f"{pname}: {annotation}" + (f" = {default}" if default is not None else ""))
    if documented:
        raise Refused(f"{where}: expected Parameters entries only for its parameters, found {', '.join(documented)}")
    result = "None" if name == "__init__" else returned(own.get("Returns"), where)
    return f"{indent}def {name}({', '.join(text)}) -> {result}: ..."


def property_stub(name, prop, where, indent):
    doc = prop.__doc__ or ""
    if not sections(doc)[""]:
        raise Refused(f"{where}: expected a docstring saying what it is, found none")
    return f"{indent}@property\n{indent}def {name}(self) -> {returned(sections(doc).get('Returns'), where)}: ..."


def class_stub(cls, where, public=()):
    doc = sections(cls.__doc__)
    if not doc[""]:
        raise Refused(f"{where}: expected a docstring saying what it is, found none")
    if issubclass(cls, enum.Enum):
        lines = [f"class {cls.__name__}(enum.Enum):"]
        lines += [f"    {m.name} = {m.value!r}" for m in cls]
        return "\n".join(lines)
    if issubclass(cls, Exception):
        return f"class {cls.__name__}(Exception): ..."
    # Bases the stub names (those among `public`, the module's stubbed classes); members
    # inherited from them are theirs, those from other bases (private ones) are listed here.
    bases = [b for b in cls.__bases__ if b.__module__ == cls.__module__ and b.__name__ in public]
    lines = [f"class {cls.__name__}({', '.join(b.__name__ for b in bases)}):" if bases else f"class {cls.__name__}:"]
    for attribute, kind in entries(doc.get("Attributes")).items():
        if kind is None:
            raise Refused(f"{where}: expected its attribute '{attribute}' as '{attribute} : type', found no type")
        lines.append(f"    {attribute}: {checked(kind, f'{where}.{attribute}')}")
    for member in members(cls, bases):
        found = inspect.getattr_static(cls, member)
        at = f"{where}.{member}"
        if isinstance(found, property) or type(found).__name__ == "property":
            lines.append(property_stub(member, found, at, "    "))
        elif isinstance(found, (staticmethod, classmethod)):
            raise Refused(f"{at}: static and class methods are not stubbed yet")
        elif callable(found):
            own = cls.__doc__ if member == "__init__" else None
            if member == "__init__" and not (inspect.isfunction(found) or "instancemethod" in type(found).__name__):
                continue
            lines.append(function_stub(member, getattr(cls, member), at, "    ", doc=own, method=True))
    return "\n".join(lines) if len(lines) > 1 else lines[0] + " ..."


def members(cls, bases=()):
    """The class's public members and kept dunders, its own and those inherited, except
    object's and those of `bases` (which their own stubs list)."""
    names = []
    for klass in reversed(cls.__mro__):
        if klass is object or any(issubclass(b, klass) for b in bases):
            continue
        for name in vars(klass):
            if (not name.startswith("_") or name in KEPT_DUNDERS) and name not in names:
                names.append(name)
    return sorted(names, key=lambda n: (n != "__init__", n))


IMPORTS = [("collections.abc", "collections.abc."), ("enum", "enum."), ("os", "os."), ("typing", "typing."),
           ("numpy", "numpy"), ("numpy.typing", "numpy.typing.")]


def module_text(blocks, extra_imports=()):
    body = "\n\n\n".join(blocks)
    imports = [f"import {module}" for module, use in IMPORTS if use in body]
    return HEADER + "\n".join(imports + list(extra_imports)) + "\n\n\n" + body + "\n"


def stubs():
    """{file name: text} of the three stubs."""
    import mgrl
    import mgrl.compare
    import mgrl.env

    if mgrl.env._gym is not None:
        raise Refused("expected a module without Gymnasium on the path (the stubs describe mgrl's own spaces), "
                      f"found Gymnasium at {mgrl.env._gym.__file__}")
    out = {}

    def blocks_of(module, names, prefix):
        blocks = []
        for name in names:
            value = getattr(module, name)
            where = f"{prefix}.{name}"
            if inspect.isclass(value):
                blocks.append(class_stub(value, where, names))
            elif callable(value):
                blocks.append(function_stub(name, value, where))
            else:
                raise Refused(f"{where}: expected a class or a function, found {type(value).__name__}")
        return blocks

    env_names = ["AutoresetMode", "Space", "Discrete", "MultiDiscrete", "Box", "Dict", "MotionGraphEnv",
                 "MotionGraphVectorEnv", "batch_space", "draw_top_down"]
    out["env.pyi"] = module_text(blocks_of(mgrl.env, env_names, "mgrl.env"), ["from . import Session"])
    compare = sys.modules["mgrl.compare"]  # mgrl.compare is the function of that name
    out["compare.pyi"] = module_text(blocks_of(compare, ["Observer", "compare", "text"], "mgrl.compare"),
                                     ["from . import Session"])
    own = [n for n in mgrl.__all__ + ["inspect"]
           if getattr(mgrl, n).__module__ in ("mgrl", "mgrl._core")]
    reexported = sorted(set(mgrl.__all__) - set(own))
    lines = [f"from .{getattr(mgrl, n).__module__.split('.')[-1]} import {n} as {n}" for n in reexported]
    blocks = ["__version__: str\n__all__: list[str]"] + blocks_of(mgrl, own, "mgrl")
    out["__init__.pyi"] = module_text(blocks, lines)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="fail when the stubs there differ from the module's")
    parser.add_argument("folder", nargs="?", default=str(ROOT / "python" / "mgrl"))
    args = parser.parse_args()
    folder = pathlib.Path(args.folder)
    try:
        made = stubs()
    except Refused as error:
        sys.exit(f"python_stubs: {error}")
    drift = []
    for name, text in made.items():
        path = folder / name
        if args.check:
            have = path.read_text() if path.exists() else ""
            if have != text:
                drift.append("".join(difflib.unified_diff(have.splitlines(True), text.splitlines(True),
                                                          f"{path} (in the tree)", f"{path} (from the module)")))
        else:
            path.write_text(text)
    if drift:
        sys.exit("python_stubs: expected the stubs to match the module, found them different; run "
                 "`PYTHONPATH=build/python python3 scripts/python_stubs.py` and commit:\n" + "\n".join(drift))
    print(f"python_stubs: {'checked' if args.check else 'wrote'} {', '.join(made)} in {folder}")


if __name__ == "__main__":
    main()
