"""The kinds of a chain's one-coordinate joints: revolute (q in rad) and prismatic (q in m).

Their own module so that gpme_core.rfem, which adds the revolute joints of its
spring-damping elements, needs nothing of gpme_core.model, whose builder calls rfem
(ChainBuilder.add_beam); gpme_core.model imports them from here and is where users take
them from (``from gpme_core.model import REVOLUTE``).
"""
REVOLUTE = "revolute"
PRISMATIC = "prismatic"
JOINT_KINDS = (REVOLUTE, PRISMATIC)
