"""Population optimizers sharing one protocol (see :mod:`.base`)."""

from .base import Objective, Optimizer, OptimizerResult
from .ftlbo import ftlbo

OPTIMIZERS: dict[str, Optimizer] = {"ftlbo": ftlbo}

__all__ = ["OPTIMIZERS", "Objective", "Optimizer", "OptimizerResult", "ftlbo"]
