"""The non-associative limit analysis on a small L wall: minutes where the pushover takes
a fraction of a second, and a multiplier 20-26 % above the pushover's certified one.

Found by the new-user sweep (session 17, docs/new_user_sweep.md): ``masonry-dem limit
--non-associative`` on an L wall of 4 x b facade, a 3-block return, 4 or 6 courses (29 or
43 blocks, dry, mu 0.7, tilted along e3) took 74 s and 151 s (load about 3 on 2 cores) for
lambda 0.3349 and 0.2822, where the pushover, certified against the associative bound,
gives 0.2790 and 0.2242 in 0.1-0.4 s. The non-associative multiplier is documented as an
estimate, not a bound (docs/limit_analysis.md); what is reported is its time on a wall this
small and its distance from the certified answer. Prints both, in one run.

    PYTHONPATH=src python benchmarks/new_user_limit_l_wall.py [--courses 4 6]
"""

from __future__ import annotations

import argparse
import time

import masonry_dem as md


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--courses", type=int, nargs="+", default=[4])
    args = parser.parse_args(argv)
    for courses in args.courses:
        wall = md.l_wall(4, courses, 0.081, 0.21, 0.07, 20e3, return_blocks=3)
        blocks, base = md.add_base(wall)
        model = md.Model.build(
            blocks,
            md.InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7),
            [md.Support([base])],
            [md.SelfWeight(), md.WeightProportional((0, 0, 1))],
            name=f"L wall, {courses} courses",
        )
        t0 = time.perf_counter()
        history = md.pushover(model)
        t1 = time.perf_counter()
        la = md.limit_analysis(model, associative=False)
        t2 = time.perf_counter()
        print(
            f"{model.name} ({blocks.count} blocks): pushover {history.status} "
            f"{history.final_load_factor:.5f} in {t1 - t0:.2f} s; non-associative limit "
            f"analysis {la.status} {la.load_factor:.5f} in {t2 - t1:.1f} s "
            f"({la.load_factor / history.final_load_factor - 1:+.1%}, "
            f"{(t2 - t1) / (t1 - t0):.0f}x the time)"
        )


if __name__ == "__main__":
    main()
