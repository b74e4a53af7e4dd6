"""Compare two `gpme verify` reports check by check (issue 25: behaviour unchanged across a
restructuring): the checks only in one, the checks whose status changed, and the checks
whose worst error changed most (as a factor).

    python tools/compare_summaries.py BEFORE/summary.json AFTER/summary.json

Exit status 0 when the same checks have the same statuses, 1 otherwise.
"""
import argparse
import json
import math
import sys


def checks(path):
    """{check name: its record} of a summary.json."""
    with open(path, encoding="utf-8") as fh:
        return {c["name"]: c for c in json.load(fh)["checks"]}


def error_factor(a, b):
    """|log10| of the ratio of two worst errors (inf when one is 0 and the other not)."""
    if a == b:
        return 0.0
    if not a or not b:
        return math.inf
    return abs(math.log10(b / a))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before")
    parser.add_argument("after")
    parser.add_argument("--worst", type=int, default=8, help="changed errors to list")
    args = parser.parse_args(argv)
    a, b = checks(args.before), checks(args.after)
    only_a, only_b = sorted(set(a) - set(b)), sorted(set(b) - set(a))
    changed = sorted(k for k in set(a) & set(b) if a[k]["status"] != b[k]["status"])
    print(f"checks: {len(a)} before, {len(b)} after; only before {len(only_a)}, only after "
          f"{len(only_b)}, status changed {len(changed)}")
    for k in only_a:
        print(f"  only before: {k} ({a[k]['status']})")
    for k in only_b:
        print(f"  only after:  {k} ({b[k]['status']})")
    for k in changed:
        print(f"  status: {k}: {a[k]['status']} -> {b[k]['status']}")
    moved = sorted(((error_factor(a[k].get("worst_abs_error"), b[k].get("worst_abs_error")), k)
                    for k in set(a) & set(b)
                    if a[k].get("worst_abs_error") is not None
                    and b[k].get("worst_abs_error") is not None), reverse=True)
    moved = [m for m in moved if m[0] > 0][:args.worst]
    if moved:
        print("largest changes of the worst error:")
    for _, k in moved:
        print(f"  {k}: {a[k]['worst_abs_error']:.3g} -> {b[k]['worst_abs_error']:.3g}")
    return 0 if not (only_a or only_b or changed) else 1


if __name__ == "__main__":
    sys.exit(main())
