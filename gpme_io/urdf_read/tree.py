"""The kinematic tree of a URDF's links and joints, and the chain or tree read from it.

:func:`_tree` checks that the joints form one tree (no link the child of two joints, no
cycle, one root, every link reached) before anything walks it; every walk visits each
link and joint a bounded number of times, whatever a hostile file holds.  :func:`_path`,
:func:`_subtree_joints` and :func:`_select_chain` read the tree: the chain is the moving
joints on the path from the chain's root link to its tip link.  :func:`_select_tree`
takes every moving joint below a root link instead (a model whose branches all move),
parents before children.
"""
from dataclasses import dataclass
from typing import Optional, Sequence

# what a failed stage leaves unchecked, said at the end of its problem
_TREE_SKIPPED = ("; not checked because of it: the chain, frozen joints, the side file "
                 "against the URDF, flexible links and the assembled model (they need one "
                 "tree)")
_CHAIN_SKIPPED = ("; not checked because of it: frozen joints, the side file against the "
                  "URDF, flexible links and the assembled model (they need a chain)")


@dataclass
class _Tree:
    """Links and joints known to form one tree."""

    root: str
    children: dict            # link -> [joints]
    parent_joint: dict        # link -> joint


_TREE_RULE = ("a URDF is a tree: every link but the root is the child of exactly one joint, "
              "and no joint leads back to a link above its parent")


def _first_cycle(links, joints) -> Optional[list]:
    """The joints of the first directed cycle of links -> child links (in cycle order, the
    joint that closes it last), or None; an iterative depth-first search that visits each
    link and joint once."""
    out = {n: [] for n in links}
    for j in joints:
        if j.parent in out and j.child in out:
            out[j.parent].append(j)
    state = {}                       # link -> 1 on the current path, 2 finished
    for start in links:
        if start in state:
            continue
        path = []                    # joints from start to the link on top of the stack
        stack = [(start, iter(out[start]))]
        state[start] = 1
        while stack:
            link, todo = stack[-1]
            j = next(todo, None)
            if j is None:
                state[link] = 2
                stack.pop()
                if path:
                    path.pop()
                continue
            if state.get(j.child) == 1:          # back to a link on the path: a cycle
                if j.child == link:
                    return [j]
                first = next(k for k, p in enumerate(path) if p.parent == j.child)
                return path[first:] + [j]
            if j.child not in state:
                state[j.child] = 1
                path.append(j)
                stack.append((j.child, iter(out[j.child])))
    return None


# names listed in a tree problem: a hostile URDF may give thousands (a 50 000-link cycle)
_LISTED = 12


def _listed(names) -> str:
    """['a', 'b', ...] of a list of names; past _LISTED names the first and last few and
    the count."""
    names = list(names)
    if len(names) <= _LISTED:
        return str(names)
    half = _LISTED // 2
    return (str(names[:half])[:-1] + ", ..., " + str(names[-half:])[1:]
            + f" ({len(names)} in all)")


def _cycle_problem(cycle) -> str:
    """The problem of a cycle of joints (from :func:`_first_cycle`), its links and joints
    listed."""
    closing = cycle[-1]
    links = [closing.child] + [j.child for j in cycle]
    if len(links) > _LISTED:
        half = _LISTED // 2
        links = links[:half] + [f"... ({len(cycle) - _LISTED + 1} more links)"] + links[-half:]
    return (f"joint {closing.name!r} (parent {closing.parent!r}, child {closing.child!r}) "
            f"closes a cycle {' -> '.join(links)} through joints "
            f"{_listed(j.name for j in cycle)}")


def _tree(links, joints, problems, left_out=()):
    """The tree of ``links`` through ``joints``, or None with the problems appended: a link
    that is the child of several joints, a cycle of joints (the first found, with its
    joints), no single root, links not reached from the root.  Every check visits each link
    and joint a bounded number of times; nothing walks the joints before they are known to
    form a tree.  ``left_out``: joints not in it (named in the problem)."""
    why = (f" (joints {left_out} are left out of the tree because of their problems above)"
           if left_out else "")
    if not links:
        problems.append("the URDF has no <link> (a <robot> needs at least one <link name=...>)"
                        + _TREE_SKIPPED)
        return None
    children = {n: [] for n in links}
    parents = {}                      # link -> [joints whose child it is]
    for j in joints:
        if j.parent in children and j.child in children:
            children[j.parent].append(j)
            parents.setdefault(j.child, []).append(j)
    found = [f"link {link!r} is the child of {len(js)} joints {_listed(j.name for j in js)}"
             for link, js in parents.items() if len(js) > 1]
    cycle = _first_cycle(links, joints)
    if cycle is not None:
        found.append(_cycle_problem(cycle))
    if found:
        found[-1] += f"; {_TREE_RULE}"
    roots = [n for n in links if n not in parents]
    if len(roots) != 1:
        loop = "; every link is some joint's child, so the joints form a loop" if not roots \
            else ""
        found.append(f"the URDF must have exactly one root link (a link that is no joint's "
                     f"child), found {_listed(roots)}{loop}{why}")
    else:
        reached, todo = {roots[0]}, [roots[0]]
        while todo:
            for j in children[todo.pop()]:
                if j.child not in reached:
                    reached.add(j.child)
                    todo.append(j.child)
        lost = [n for n in links if n not in reached]
        if lost:
            found.append(f"links {_listed(lost)} are not connected to the root link "
                         f"{roots[0]!r} (a cycle of joints?){why}")
    if found:
        found[-1] += _TREE_SKIPPED
        problems.extend(found)
        return None
    return _Tree(roots[0], children, {link: js[0] for link, js in parents.items()})


def _path(tree, top, bottom):
    """Joints from link ``top`` down to link ``bottom`` (None if bottom is not below top);
    at most one step per link, whatever the tree holds."""
    out, link = [], bottom
    for _ in range(len(tree.children) + 1):
        if link == top:
            return out[::-1]
        j = tree.parent_joint.get(link)
        if j is None:
            return None
        out.append(j)
        link = j.parent
    return None


def _subtree_joints(tree, link):
    """Joints below link ``link`` (depth first); each link is entered once."""
    out, stack, seen = [], [link], {link}
    while stack:
        for j in tree.children[stack.pop()]:
            out.append(j)
            if j.child not in seen:
                seen.add(j.child)
                stack.append(j.child)
    return out


def _select_chain(tree, chain, frozen, problems):
    """(root, tip, chain joints) or None; appends the problems of the chain choice."""
    root, tip = tree.root, None
    if chain is not None:
        if isinstance(chain, str) or not isinstance(chain, Sequence) or not 1 <= len(chain) <= 2:
            problems.append(f"chain must be (root link, tip link) or (root link,), got {chain!r}")
            return None
        root = tree.root if chain[0] is None else chain[0]
        tip = chain[1] if len(chain) == 2 else None
        bad = [f"{what} {name!r}" for what, name in (("root", root), ("tip", tip))
               if name is not None and name not in tree.children]
        if bad:
            problems.append(f"chain {', '.join(bad)}: not a link of the file; links: "
                            f"{sorted(tree.children)}")
            return None
    if tip is None:
        candidates = [j for j in _subtree_joints(tree, root) if j.moving and j.name not in frozen]
        if not candidates:
            problems.append(f"no revolute, continuous or prismatic joint below link {root!r} "
                            "(frozen joints do not count)")
            return None
        names = {j.name for j in candidates}
        leaves = [j for j in candidates
                  if not any(k.name in names for k in _subtree_joints(tree, j.child))]
        if len(leaves) > 1:
            ends = [j.child for j in leaves]
            problems.append(f"the moving joints below link {root!r} lie on {len(ends)} "
                            f"branches ending at links {ends}: choose one with "
                            f"chain=({root!r}, <tip link>); the joints off it are frozen "
                            "(frozen={name: value}, default 0)")
            return None
        tip = leaves[0].child
    path = _path(tree, root, tip)
    if path is None:
        problems.append(f"chain tip {tip!r} is not below the chain root {root!r} (the path "
                        f"from the URDF root {tree.root!r} to {tip!r} is "
                        f"{[j.name for j in _path(tree, tree.root, tip)]})")
        return None
    moving = [j for j in path if j.moving]
    if not moving:
        problems.append(f"the chain {root!r} -> {tip!r} has no revolute, continuous or "
                        "prismatic joint")
        return None
    return root, tip, moving


def _preorder_joints(tree, link):
    """Joints below link ``link``, each before the joints below it, siblings in the file's
    order (depth first, pre-order: Pinocchio's and MuJoCo's numbering); each link is
    entered once."""
    out, stack, seen = [], [iter(tree.children[link])], {link}
    while stack:
        j = next(stack[-1], None)
        if j is None:
            stack.pop()
            continue
        out.append(j)
        if j.child not in seen:
            seen.add(j.child)
            stack.append(iter(tree.children[j.child]))
    return out


def _select_tree(tree, root, frozen, problems):
    """(root, None, moving joints below ``root`` not in ``frozen``, parents first) or None;
    appends the problems of the choice (an unknown root, no moving joint)."""
    root = tree.root if root is None else root
    if root not in tree.children:
        problems.append(f"tree root {root!r}: not a link of the file; links: "
                        f"{sorted(tree.children)}")
        return None
    moving = [j for j in _preorder_joints(tree, root) if j.moving and j.name not in frozen]
    if not moving:
        problems.append(f"no revolute, continuous or prismatic joint below link {root!r} "
                        "(frozen joints do not count)")
        return None
    return root, None, moving
