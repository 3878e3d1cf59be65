"""kn = 1e300 through the Python API: an exception escapes the pushover instead of a status.

The case-file schema refuses kn above 1e14 (``cases.schema.RANGES``), but
``InterfaceMaterial`` takes any positive kn, as its tests need (friction 1e10 in
tests/solvers/test_certificate.py). docs/solvers.md records the held 3 x 5 panel with
kn = 1e300 ending in a certified collapse; a free-standing 2 x 3 wall on a base (t/H =
0.288) instead raises ``SingularMatrix`` out of ``pushover`` (found by the new-user sweep,
session 17). Expected: a status (``failed`` or ``collapse``) with its reason, as every other
failure of the solver ends.

    PYTHONPATH=src python benchmarks/new_user_huge_stiffness.py
"""

from __future__ import annotations

import masonry_dem as md


def main() -> None:
    wall = md.running_bond_wall(
        2, 3, block_height=0.081, block_length=0.21, thickness=0.07, unit_weight=20e3
    )
    blocks, base = md.add_base(wall)
    for kn, kt in ((1e14, 0.4e14), (1e300, 1e9), (1e300, 0.4e300)):
        model = md.Model.build(
            blocks,
            md.InterfaceMaterial(kn=kn, kt=kt, friction=0.7),
            supports=[md.Support([base])],
            loads=[md.SelfWeight(), md.WeightProportional(direction=(0, 0, 1))],
        )
        try:
            history = md.pushover(model)
            got = f"{history.status} at {history.final_load_factor:.6g}: {history.reason[:160]}"
        except Exception as exc:  # noqa: BLE001 - the defect this script shows
            got = f"raised {type(exc).__module__}.{type(exc).__name__}: {exc}"
        print(f"kn={kn:g} kt={kt:g}: expected a status (t/H = 0.288); got {got}")


if __name__ == "__main__":
    main()
