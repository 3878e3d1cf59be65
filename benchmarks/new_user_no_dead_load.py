"""A wall whose joints carry no dead load: the live load finds no equilibrium above lambda = 0.

A new user's mistake (sweep, session 17): the case's only load is live, so the dry joints
(tensile strength 0) carry no normal force and friction holds nothing. Either the live load
alone (``weight_proportional`` along e3, no self weight) or the self weight made live with it
(lateral load = weight at every lambda, beyond the free wall's t/H = 0.288) has no
equilibrium at any lambda > 0: the expected answer is a collapse at lambda = 0 (or a refusal
naming the missing dead load). Prints what the pushover says and how long it took, with the
default settings and with ``max_steps = 40``: ``max_steps`` is documented as the converged
steps of a run, but the load-control loop counts every attempt, and the bracket at lambda = 0
halves down to 1e-12 of the load scale (about 45 failed attempts), so with 40 the run ends
``failed: max_steps=40 reached at lambda=0`` after one recorded step.

    PYTHONPATH=src python benchmarks/new_user_no_dead_load.py
"""

from __future__ import annotations

import time

import masonry_dem as md


def main() -> None:
    wall = md.running_bond_wall(
        2, 3, block_height=0.081, block_length=0.21, thickness=0.07, unit_weight=20e3
    )
    blocks, base = md.add_base(wall)
    cases = {
        "live tilt, no self weight": [md.WeightProportional(direction=(0, 0, 1))],
        "live self weight + live tilt 1:1": [
            md.SelfWeight(live=True),
            md.WeightProportional(direction=(0, 0, 1)),
        ],
    }
    for label, loads in cases.items():
        model = md.Model.build(
            blocks,
            md.InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7),
            supports=[md.Support([base])],
            loads=loads,
        )
        for settings in (md.StaticSettings(), md.StaticSettings(max_steps=40)):
            t0 = time.perf_counter()
            history = md.pushover(model, settings)
            seconds = time.perf_counter() - t0
            print(
                f"{label}, max_steps={settings.max_steps}: expected collapse at 0; got "
                f"{history.status} at lambda {history.final_load_factor:.6g} after "
                f"{len(history.steps)} recorded steps in {seconds:.1f} s: {history.reason}"
            )


if __name__ == "__main__":
    main()
