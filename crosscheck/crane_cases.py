"""The paper's crane cases each engine checks when no model file is given, defined once
(`gpme verify`, `gpme crosscheck ENGINE`, each engine's default_scenarios).

CASES[engine][quick]: the RFEM segment counts n of the arm (0 = rigid) and whether the run
starts on the constraints (gpme_io.scenario.crane_scenario).  Pinocchio and Drake compare
terms at sampled states: rigid and n = 1, 3, 10 (quick: rigid and n = 3, the CI budget; n =
10 adds nothing a quick run could see that n = 3 does not).  MuJoCo and Exudyn realise the
programmed runs from a consistent start: rigid and n = 1 (MuJoCo's soft equality mechanism
is studied on the smallest flexible arm), rigid and n = 3 (Exudyn, the paper's arm).  The
continuum step judges the paper's flexible arm (n = 3) against geometrically exact beams.
"""
from gpme_io.scenario import crane_scenario

TERMS_FULL, TERMS_QUICK = (0, 1, 3, 10), (0, 3)
CASES = {
    "pinocchio": {False: (TERMS_FULL, False), True: (TERMS_QUICK, False)},
    "drake": {False: (TERMS_FULL, False), True: (TERMS_QUICK, False)},
    "mujoco": {False: ((0, 1), True), True: ((0, 1), True)},
    "exudyn": {False: ((0, 3), True), True: ((0, 3), True)},
    "gpme": {False: ((0, 3), False), True: ((0, 3), False)},
    "continuum": {False: ((3,), True), True: ((3,), True)},
}


def crane_cases(engine: str, quick: bool) -> list:
    """[Scenario] of the paper's crane that ``engine`` checks by default."""
    segments, on_constraints = CASES[engine][bool(quick)]
    return [crane_scenario(n, on_constraints=on_constraints) for n in segments]
