"""Which model names MuJoCo cannot take, found before any work."""
from gpme_core.errors import ModelError

from .cases import programme
from .mjcf import name_problems


def scenario_name_problems(scenarios) -> None:
    """Raise ModelError listing the names of ``scenarios`` that MuJoCo cannot take (repeated
    in one of its namespaces, empty, not XML characters: crosscheck.mujoco.mjcf.name_problems)."""
    problems = [f"{s.name}: {p}" for s in scenarios
                for p in name_problems(s.model, programme(s))]
    if problems:
        raise ModelError(problems)
