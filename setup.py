"""pip install . : the module `mgrl` built through CMake (the target mgrl_python, with
Debian's pybind11-dev) and installed with its Python files and the scenarios.

    pip install --no-build-isolation .     (offline; into a venv, --user, or the system)

MGRL_BUILD_DIR=DIR builds in that CMake build folder (an existing build: nothing is
compiled again); otherwise in setuptools' build folder, with ccache when it is there.
The version is the top-level CMakeLists.txt's project() version."""
import os
import pathlib
import re
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py

ROOT = pathlib.Path(__file__).resolve().parent


def version():
    text = (ROOT / "CMakeLists.txt").read_text()
    found = re.search(r"project\(mgrl VERSION ([0-9.]+)", text)
    if not found:
        sys.exit("setup.py: expected 'project(mgrl VERSION X.Y.Z' in CMakeLists.txt, found none")
    return found.group(1)


class CMakeBuild(build_ext):
    """Builds mgrl_python with CMake and copies the module where setuptools expects it."""

    def build_extension(self, ext):
        build = pathlib.Path(os.environ.get("MGRL_BUILD_DIR") or pathlib.Path(self.build_temp).resolve() / "cmake")
        for tool in ("cmake", "ninja"):
            if shutil.which(tool) is None:
                sys.exit(f"setup.py: expected {tool} on PATH, found none (scripts/setup.sh --python installs it)")
        env = dict(os.environ)
        if not (build / "CMakeCache.txt").exists():
            # A venv's interpreter is its base's: the module is built for that one (same ABI).
            python = getattr(sys, "_base_executable", sys.executable)
            configure = ["cmake", "-S", str(ROOT), "-B", str(build), "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                         "-DMGRL_PYTHON=ON", f"-DPython_EXECUTABLE={python}", "-DMGRL_BUILD_TESTS=OFF",
                         "-DMGRL_BUILD_BENCH=OFF"]
            if shutil.which("ccache"):
                configure.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
                env.setdefault("CCACHE_BASEDIR", str(ROOT))
            subprocess.run(configure, check=True, env=env)
        # An existing build folder is built as it was configured (its own Python, its options).
        cache = (build / "CMakeCache.txt").read_text()
        if "MGRL_PYTHON:BOOL=ON" not in cache:
            sys.exit(f"setup.py: expected {build} configured with the Python module (MGRL_PYTHON=ON), found it "
                     "without: install pybind11-dev (scripts/setup.sh --python) and configure it again")
        subprocess.run(["cmake", "--build", str(build), "--target", "mgrl_python", "-j", str(os.cpu_count() or 2)],
                       check=True, env=env)
        built = sorted((build / "python" / "mgrl").glob("_core*.so"))
        if len(built) != 1:
            sys.exit(f"setup.py: expected one _core*.so in {build / 'python' / 'mgrl'}, found {len(built)}: is "
                     "pybind11-dev installed?")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)


class BuildPy(build_py):
    """The Python files, and the scenarios beside them (mgrl.scenario_path)."""

    def run(self):
        super().run()
        scenarios = pathlib.Path(self.build_lib) / "mgrl" / "scenarios"
        scenarios.mkdir(parents=True, exist_ok=True)
        for source in sorted((ROOT / "scenarios").glob("*.yaml")) + [ROOT / "scenarios" / "README.md"]:
            shutil.copyfile(source, scenarios / source.name)


# setuptools' own build folder, apart from CMake's build/ beside it.
SETUPTOOLS_BUILD = ROOT / "build" / "setuptools"
SETUPTOOLS_BUILD.mkdir(parents=True, exist_ok=True)

setup(
    version=version(),
    packages=["mgrl"],
    package_dir={"": "python"},
    package_data={"mgrl": ["*.pyi", "py.typed"]},  # the type stubs (PEP 561)
    ext_modules=[Extension("mgrl._core", sources=[])],
    cmdclass={"build_ext": CMakeBuild, "build_py": BuildPy},
    options={"build": {"build_base": str(SETUPTOOLS_BUILD)}, "egg_info": {"egg_base": str(SETUPTOOLS_BUILD)}},
    zip_safe=False,
)
