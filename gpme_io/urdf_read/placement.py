"""The chosen chain and where every URDF link sits on it.

Once the chain is chosen and every other moving joint has its frozen value, each link is
fixed to one chain link (its owner: the child link of chain joint k) or to the world, at a
constant pose in the owner's frame.  The chain links become the model's bodies; the others
merge into their owner as mass and named frames.
"""
from collections import deque
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class _Chain:
    """The chain (or tree) read: its root and tip links (tip None for a whole tree) and its
    joints (the _Joint of each gpme coordinate, in path order from the root; for a tree,
    each joint after the joint that moves its parent link)."""

    root: str
    tip: object
    joints: list

    @property
    def index(self) -> dict:
        """{joint name: chain index k}."""
        return {j.name: k for k, j in enumerate(self.joints)}

    @property
    def names(self) -> list:
        """The chain joints' names, in order."""
        return [j.name for j in self.joints]

    @property
    def links(self) -> list:
        """The chain links (the child link of each chain joint), in order."""
        return [j.child for j in self.joints]


# owner of the links fixed to the world (the URDF root link's frame)
_WORLD = -1


@dataclass(frozen=True)
class _Placement:
    """Where every link of the tree sits.

    owner        : {link: chain index k of the chain link it is fixed to; _WORLD for the
                   links fixed to the URDF root link}
    pose         : {link: (4, 4) its frame in its owner's link frame (the URDF root
                   link's frame for _WORLD)}; identity for the chain links themselves
    attached     : {k: [links merged into owner k], in breadth-first order}
    chain_origin : {k: (4, 4) chain joint k's frame in the frame of the owner of its parent
                   link (owner k - 1 in a chain; :func:`_parents` gives it for a tree)}
    """

    owner: dict
    pose: dict
    attached: dict
    chain_origin: dict


def _place(tree, chain_index, values) -> _Placement:
    """The placement of every link of ``tree`` reached from its root (breadth first), the
    joints in ``chain_index`` ({name: k}) moving and every other joint at its value in
    ``values`` ({name: rad or m}, 0 when absent)."""
    owner, pose, attached = {tree.root: _WORLD}, {tree.root: np.eye(4)}, {}
    chain_origin = {}
    stack, seen = deque([tree.root]), {tree.root}
    while stack:
        link = stack.popleft()
        for j in tree.children[link]:
            if j.child in seen:           # not in a tree (_tree refuses it); defence in depth
                continue
            seen.add(j.child)
            if j.name in chain_index:
                k = chain_index[j.name]
                chain_origin[k] = pose[link] @ j.origin
                owner[j.child], pose[j.child] = k, np.eye(4)
            else:
                owner[j.child] = owner[link]
                pose[j.child] = pose[link] @ j.origin @ j.motion(values.get(j.name, 0.0))
                attached.setdefault(owner[link], []).append(j.child)
            stack.append(j.child)
    return _Placement(owner, pose, attached, chain_origin)


def _parents(chain, placement) -> list:
    """[parent index of each chain joint]: the owner of the joint's parent link (_WORLD =
    -1 for a link fixed to the URDF root), the gpme_core.model.Model.parents of the model."""
    return [placement.owner[j.parent] for j in chain.joints]
