# The mgrl module's type stubs, made by scripts/python_stubs.py from the module's own
# signatures and docstrings; CI fails when they differ from what it gives.
import collections.abc
import os
import typing
import numpy
import numpy.typing
from . import Session


class Observer:
    budget: int
    snapshot_count: int
    snapshot_points: list[int]
    snapshots: list[dict[str, typing.Any]]
    def __init__(self, budget: int, count: int) -> None: ...
    def progress(self, updates: int, total: int | None = None) -> None: ...
    def snapshot(self, table: numpy.typing.ArrayLike, updates: int, residual: float | None = None) -> None: ...


def compare(session: Session, behavior: str, learners: collections.abc.Sequence[typing.Any], seeds: collections.abc.Iterable[int] = (1,), trials: int = 100, seconds: float = 10.0, snapshots: int = 10, snapshot_trials: int | None = None, budget: int = 1000000, report: str | os.PathLike[str] | None = None, log: collections.abc.Callable[..., object] | None = ...) -> dict[str, typing.Any]: ...


def text(result: dict[str, typing.Any]) -> str: ...
