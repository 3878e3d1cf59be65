"""Quick start: a dry running-bond panel held on its left edge, tilted out of plane.

    python examples/quickstart.py --out results/quickstart

Prints the collapse multiplier with its bracket and writes the VTU/PVD series.
"""

from __future__ import annotations

import argparse

import masonry_dem as md


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", default="results/quickstart")
    parser.add_argument("--courses", type=int, default=13)
    args = parser.parse_args(argv)

    wall = md.running_bond_wall(
        3, args.courses, block_height=0.081, block_length=0.210, thickness=0.070, unit_weight=20e3
    )
    blocks, base = md.add_base(wall)
    model = md.Model.build(
        blocks,
        md.InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7),
        supports=[md.Support([base]), md.Support(md.select.column(wall, "left"), ["u1", "u3"])],
        loads=[md.SelfWeight(), md.WeightProportional(direction=(0, 0, 1))],
        name="quickstart",
    )
    history = md.pushover(model, out=args.out)
    lo, hi = history.collapse_bracket or (history.final_load_factor,) * 2
    print(f"{history.status}: lambda in [{lo:.4f}, {hi:.4f}] after {len(history.steps)} steps")
    return history.summary()


if __name__ == "__main__":
    main()
