"""The side file against the URDF it sits beside (gpme_io.side_file).

The side file's own problems (keys, records, values) are found on reading it; here its
springs, drives, massless links and RFEM records are checked to name moving joints and
links of the chain that was read.
"""
from dataclasses import dataclass


@dataclass(frozen=True)
class _SideUse:
    """What of the side file applies to the chain.

    joints   : {chain joint name: {"stiffness", "spring_reference"}}
    drives   : the drive records on chain joints
    flexible : {record name: RFEM record} whose joints and links are all in the chain
    point_springs : the point-spring records (their frames are checked by the built model)
    """

    joints: dict
    drives: list
    flexible: dict
    point_springs: list = ()


def _match_side(side, tree, chain, side_massless, problems) -> _SideUse:
    """The parts of ``side`` (a checked side-file dict, {} for none) that name the chain's
    joints and links; a problem appended for every record that names others."""
    chain_index, chain_names, chain_links = chain.index, chain.names, chain.links
    side_joints = side.get("joints", {})
    unknown = sorted(set(side_joints) - set(chain_index))
    if unknown:
        problems.append(f"the side file gives springs for joints {unknown} that are not moving "
                        f"joints of the chain {chain_names}")
    side_drives = []
    for rec in side.get("drives", []):
        if rec["joint"] in chain_index:
            side_drives.append(rec)
        else:
            problems.append(f"the side file's drive record on {rec['joint']!r} "
                            f"({rec['function']}): not a moving joint of the chain "
                            f"{chain_names}")
    unknown = [lk for lk in side_massless if lk not in tree.children]
    if unknown:
        problems.append(f"the side file's massless_links {unknown} are not links of the URDF")
    side_flex = {}
    for rec in side.get("flexible_links", []):
        lost = ([f"joint {j!r}" for j in rec["joints"] if j not in chain_index]
                + [f"link {lk!r}" for lk in rec["links"] if lk not in chain_links])
        if lost:
            problems.append(f"the side file's flexible link record {rec['name']!r} names "
                            f"{', '.join(lost)}, not in the chain (joints {chain_names}, "
                            f"links {chain_links})")
        else:
            side_flex[rec["name"]] = rec
    return _SideUse(side_joints, side_drives, side_flex, list(side.get("point_springs", [])))
