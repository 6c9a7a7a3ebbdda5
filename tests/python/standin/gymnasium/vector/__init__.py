"""The stand-in's gymnasium.vector: VectorEnv and AutoresetMode (see the package's docstring)."""
import enum

from .. import Env
from . import utils  # noqa: F401


class AutoresetMode(enum.Enum):
    NEXT_STEP = "NextStep"
    SAME_STEP = "SameStep"
    DISABLED = "Disabled"


class VectorEnv(Env):
    num_envs = 0
