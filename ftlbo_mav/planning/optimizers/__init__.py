"""Population optimizers sharing one protocol (see :mod:`.base`)."""

from .base import Objective, Optimizer, OptimizerResult, evaluation_budget
from .ftlbo import ftlbo
from .ga import ga
from .seeded import ftlbo_seeded
from .theta_pso import theta_pso
from .tlbo import tlbo

OPTIMIZERS: dict[str, Optimizer] = {
    "ftlbo-seeded": ftlbo_seeded,
    "ftlbo": ftlbo,
    "tlbo": tlbo,
    "ga": ga,
    "theta-pso": theta_pso,
}
"""Every algorithm by its ``[planner] algorithm`` name; ``ftlbo`` is the paper's."""

DEFAULT_ALGORITHM = "ftlbo-seeded"
PAPER_ALGORITHMS = ("ftlbo", "tlbo", "ga", "theta-pso")
"""The paper's comparison (Table 2), FTLBO first."""

__all__ = [
    "DEFAULT_ALGORITHM",
    "OPTIMIZERS",
    "PAPER_ALGORITHMS",
    "Objective",
    "Optimizer",
    "OptimizerResult",
    "evaluation_budget",
    "ftlbo",
    "ftlbo_seeded",
    "ga",
    "theta_pso",
    "tlbo",
]
