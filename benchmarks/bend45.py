"""The Bathe-Bolourchi 45-degree bend: RFEM and the continuum against the published tip
positions (the tables of docs/rfem-continuum.md, section "Bathe-Bolourchi 45-degree bend").

    python -m benchmarks.bend45 [--max-chords 128] [--max-elements 256]

Prints, for P = 300, 450, 600 N (positions in m, frame of crosscheck.continuum.bend45):

1. the continuum (Exudyn) at meshes doubled from 8 elements, physical rod and
   Euler-Bernoulli limit, with mesh changes, observed orders and Richardson limits;
2. RFEM with one segment per chord, chords doubled from 4: tip, difference from the
   continuum's Euler-Bernoulli limit (RFEM's limit), observed orders;
3. RFEM at 64 segments split differently between chords and segments per chord (what
   the polygon costs);
4. RFEM's extrapolated limit against the continuum's;
5. the published values, the band they support, and where the converged solutions, the
   Saint-Venant torsion constant and Kynema's number fall;
6. the sources' 8-element solutions against the continuum at 8 elements.

About 3 minutes on two cores.
"""
import argparse
import time

import numpy as np

from crosscheck.continuum import bend45 as b

FMT = "{:9.4f}"


def _vec(v) -> str:
    return " ".join(FMT.format(c) for c in v)


def _sci(v) -> str:
    return " ".join(f"{c:9.2e}" for c in v)


def _orders(o) -> str:
    return " ".join("      -  " if not np.isfinite(c) else f"{c:9.2f}" for c in o)


def continuum_table(max_elements: int):
    refs = {}
    for label, eb in (("physical rod", False), ("Euler-Bernoulli limit", True)):
        ref = b.continuum_reference(euler_bernoulli=eb, max_elements=max_elements)
        refs[eb] = ref
        print(f"\n== continuum (Exudyn), {label}: tip x y z, change from the previous mesh, "
              "observed order")
        meshes = sorted(ref.tips)
        for p in b.LOADS:
            print(f"P = {p:g} N")
            for i, m in enumerate(meshes):
                tip = ref.tips[m][p]
                change = "" if i == 0 else _sci(np.abs(tip - ref.tips[meshes[i - 1]][p]))
                order = "" if i < 2 else _orders(b.observed_order(
                    ref.tips[meshes[i - 2]][p], ref.tips[meshes[i - 1]][p], tip))
                print(f"  {m:4d} el  {_vec(tip)} | {change} | {order}")
            print(f"  limit    {_vec(ref.limit[p])}   (limit - finest {_sci(ref.error[p])})")
    return refs


def rfem_table(reference, max_chords: int):
    print("\n== RFEM, one segment per chord: tip x y z | minus the continuum's Euler-Bernoulli "
          "limit | observed order of that difference from the previous N")
    chords = [n for n in (4, 8, 16, 32, 64, 128, 256) if n <= max_chords]
    tips = {}
    for n in chords:
        start = time.perf_counter()
        tips[n] = b.solve_load_path(1, n)
        print(f"  ({n} chords: {time.perf_counter() - start:.1f} s)", flush=True)
    for p in b.LOADS:
        print(f"P = {p:g} N")
        for i, n in enumerate(chords):
            diff = tips[n][p] - reference.limit[p]
            order = "" if i < 1 else _orders(
                np.log(np.abs(tips[chords[i - 1]][p] - reference.limit[p]) / np.abs(diff))
                / np.log(2.0))
            print(f"  N = {n:4d}  {_vec(tips[n][p])} | {_vec(diff)} | {order}")
    return tips


def split_table(reference):
    print("\n== RFEM at 64 segments: chords x segments per chord, minus the continuum's "
          "Euler-Bernoulli limit (P = 600 N)")
    for chords, segments in ((64, 1), (32, 2), (16, 4), (8, 8)):
        start = time.perf_counter()
        tip = b.solve_load_path(segments, chords)[600.0]
        print(f"  {chords:3d} x {segments}  {_vec(tip)} | {_vec(tip - reference.limit[600.0])}"
              f"   ({time.perf_counter() - start:.1f} s)", flush=True)


def limit_table(tips, refs):
    print("\n== RFEM's limit (order 1 + 2 from the three finest chord counts) against the "
          "continuum")
    chords = sorted(tips)[-3:]
    for p in b.LOADS:
        lim = b.extrapolate_order_one_two(*(tips[n][p] for n in chords))
        est = np.abs(lim - b.extrapolate(tips[chords[1]][p], tips[chords[2]][p], 1.0))
        print(f"P = {p:g} N  RFEM limit {_vec(lim)} (error estimate {_sci(est)})")
        print(f"           minus EB continuum {_sci(lim - refs[True].limit[p])}; physical "
              f"minus EB continuum {_sci(refs[False].limit[p] - refs[True].limit[p])}")


def published_table(refs, max_elements):
    print("\n== published values (position x y z) and the band they support")
    sv = b.continuum_reference(torsion_constant=b.TORSION_SAINT_VENANT,
                               max_elements=max_elements)
    for p in b.LOADS:
        band = b.published_band(p)
        print(f"P = {p:g} N  band {_vec(band.lower)} .. {_vec(band.upper)}, allowed outside "
              f"{_vec(band.width)}")
        for e in band.sources:
            print(f"  {e.source:45s} {_vec(e.position)}  (+-{e.half_unit:g})")
        for label, pos in (("continuum, physical, G J = G (I_y + I_z)", refs[False].limit[p]),
                           ("continuum, Euler-Bernoulli", refs[True].limit[p]),
                           ("continuum, physical, G J Saint-Venant", sv.limit[p])):
            out = b.outside_band(pos, band)
            verdict = "inside the allowance" if np.all(out <= band.width) else "OUTSIDE"
            print(f"  {label:45s} {_vec(pos)}  outside by {_sci(out)}: {verdict}")
    for e in (b.BEAMDYN_2015, b.KYNEMA):
        print(f"  {e.source:45s} {_vec(e.position)}  minus physical continuum "
              f"{_vec(np.asarray(e.position) - refs[False].limit[e.load])}")


def eight_element_table():
    print("\n== the sources' 8-element meshes: Exudyn with 8 linear elements (physical rod)")
    tips = b.exudyn_tip(8)
    for e in b.PUBLISHED:
        if "Simo" in e.source:
            print(f"P = {e.load:g} N  Simo & Vu-Quoc {_vec(e.position)}  Exudyn(8) "
                  f"{_vec(tips[e.load])}  difference {_vec(np.asarray(e.position) - tips[e.load])}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-chords", type=int, default=128)
    parser.add_argument("--max-elements", type=int, default=256)
    args = parser.parse_args(argv)
    start = time.perf_counter()
    refs = continuum_table(args.max_elements)
    tips = rfem_table(refs[True], args.max_chords)
    split_table(refs[True])
    limit_table(tips, refs)
    published_table(refs, args.max_elements)
    eight_element_table()
    print(f"\n{time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
