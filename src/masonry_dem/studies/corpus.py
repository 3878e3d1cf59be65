"""The walls the static solver is judged on (``benchmarks/agreement.py``): the paper's
validation cases, two walls that were never used to tune the solver (each over kt/kn and
kn), and walls drawn at random from the classes an engineer models (in and out of plane,
1-15 blocks by 1-20 courses, openings with lintels, held columns, walls that meet, friction
0.3-10, kt/kn 0.1-1). A wall is a name and a function that builds its model, so that a
corpus of hundreds costs nothing until a wall is run.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np

from masonry_dem.geometry import selectors as select
from masonry_dem.geometry.builders import add_base, cut_openings, running_bond_wall
from masonry_dem.geometry.plans import l_wall, u_wall
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional

IN_PLANE = (1.0, 0.0, 0.0)
OUT_OF_PLANE = (0.0, 0.0, 1.0)


@dataclass(frozen=True)
class CorpusWall:
    """One wall of the corpus: its ``name``, the set it belongs to, and how to build it."""

    name: str
    group: str
    build: Callable[[], Model]
    describe: dict[str, Any] = field(default_factory=dict)


def _on_base(
    blocks: Any,
    material: InterfaceMaterial,
    direction: tuple[float, float, float],
    held: str = "none",
    name: str = "wall",
) -> Model:
    """``blocks`` on a rigid base, under self weight and lambda x the weight along
    ``direction``; ``held``: the end columns held in u1 and u3 (``left``, ``both``)."""
    wall = np.arange(blocks.count)
    placed, base = add_base(blocks)
    supports = [Support([base])]
    if held in ("left", "both"):
        supports.append(Support(select.column(placed, "left", among=wall), ["u1", "u3"]))
    if held == "both":
        supports.append(Support(select.column(placed, "right", among=wall), ["u1", "u3"]))
    return Model.build(
        placed, material, supports, [SelfWeight(), WeightProportional(direction)], name=name
    )


def windows_wall(kn: float = 1e10, kt_over_kn: float = 0.4) -> Model:
    """8 x 10 running bond of 0.25 x 0.10 x 0.12 m blocks, two windows with lintels, fixed
    base, in-plane tilt, friction 0.5 (issue 36: certified 30 % below the reference)."""
    wall = running_bond_wall(8, 10, 0.1, 0.25, 0.12, 18e3)
    wall = cut_openings(wall, [(0.25, 0.4, 0.75, 0.7), (1.25, 0.4, 1.75, 0.7)], lintels=True)
    material = InterfaceMaterial(kn=kn, kt=kt_over_kn * kn, friction=0.5)
    return _on_base(wall, material, IN_PLANE, name=f"windows_kn{kn:.0e}_r{kt_over_kn}")


def pier_wall(kn: float = 1e9, kt_over_kn: float = 0.4, courses: int = 10) -> Model:
    """5 blocks of 0.4 x 0.175 x 0.2 m a course, half blocks at the ends of the bottom
    course, fixed base, friction 10, in-plane tilt (issue 36: moved 41 % with kt/kn)."""
    wall = running_bond_wall(5, courses, 0.175, 0.4, 0.2, 20e3, start_with_half=True)
    material = InterfaceMaterial(kn=kn, kt=kt_over_kn * kn, friction=10.0)
    return _on_base(wall, material, IN_PLANE, name=f"pier{courses}_kn{kn:.0e}_r{kt_over_kn}")


def validation_walls() -> Iterator[CorpusWall]:
    """The paper's 18 validation cases (Tables 1-3), as built by :mod:`masonry_dem.cases.paper`."""
    from masonry_dem.cases.paper import case_names

    for name in case_names():
        yield CorpusWall(name, "validation", partial(_case_model, name))


def _case_model(name: str) -> Model:
    from masonry_dem.cases.paper import build_case

    return build_case(name).model


def issue_walls() -> Iterator[CorpusWall]:
    """The two walls of issue 36 at kt/kn 0.1, 0.4, 0.417, 1 (kn at its stated value) and
    at kn 1e8 to 1e11 (kt/kn 0.4), and the pier wall's 6-course sibling."""
    for ratio in (0.1, 0.4, 0.417, 1.0):
        yield CorpusWall(
            f"windows r{ratio}", "issue", partial(windows_wall, 1e10, ratio), {"kt/kn": ratio}
        )
        yield CorpusWall(
            f"pier r{ratio}", "issue", partial(pier_wall, 1e9, ratio), {"kt/kn": ratio}
        )
    for kn in (1e8, 1e9, 1e11):
        yield CorpusWall(f"windows kn{kn:.0e}", "issue", partial(windows_wall, kn), {"kn": kn})
    for kn in (1e8, 1e10, 1e11):
        yield CorpusWall(f"pier kn{kn:.0e}", "issue", partial(pier_wall, kn), {"kn": kn})
    yield CorpusWall("pier6 r0.4", "issue", partial(pier_wall, 1e9, 0.4, 6))


def random_wall(seed: int) -> CorpusWall:
    """A wall drawn from the classes of the corpus by ``numpy.random.default_rng(seed)``:
    the same seed builds the same wall on every machine."""
    rng = np.random.default_rng(seed)
    kind = str(rng.choice(["flat", "flat", "openings", "held", "meets"]))
    direction = IN_PLANE if rng.random() < 0.5 else OUT_OF_PLANE
    a = float(rng.uniform(0.05, 0.25))
    b = float(rng.uniform(1.2, 3.0) * a)
    s = float(rng.uniform(0.05, 0.3))
    friction = float(np.exp(rng.uniform(np.log(0.3), np.log(10.0))))
    ratio = float(rng.uniform(0.1, 1.0))
    kn = float(10 ** rng.uniform(8.0, 11.0))
    material = InterfaceMaterial(kn=kn, kt=ratio * kn, friction=friction)
    held = "none"
    if kind == "meets":
        n = int(rng.integers(3, 9))
        courses = int(rng.integers(3, 13))
        returns = int(rng.integers(1, 4))
        s = min(s, float(rng.uniform(0.3, 0.5)) * b)  # a corner interlocks s within b
        plan = str(rng.choice(["l", "u"]))
        builder = l_wall if plan == "l" else u_wall
        blocks = builder(n, courses, a, b, s, 18e3, return_blocks=returns)
        direction = OUT_OF_PLANE
        shape = f"{plan}-wall {n}x{courses} returns {returns}"
    else:
        n = int(rng.integers(1, 16))
        courses = int(rng.integers(1, 21))
        if kind == "openings":
            n, courses = max(n, 5), max(courses, 5)
        blocks = running_bond_wall(
            n, courses, a, b, s, 18e3, start_with_half=bool(rng.random() < 0.5)
        )
        shape = f"{n}x{courses}"
        if kind == "openings":
            # one window of 1-3 blocks by 1-3 courses, at least one block from each edge and
            # a course above it for its lintel
            width = int(rng.integers(1, min(3, n - 2) + 1))
            height = int(rng.integers(1, min(3, courses - 3) + 1))
            x0 = int(rng.integers(1, n - width))
            y0 = int(rng.integers(1, courses - height - 1))
            box = (x0 * b, y0 * a, (x0 + width) * b, (y0 + height) * a)
            blocks = cut_openings(blocks, [box], lintels=True)
            shape += f" window {width}x{height}"
        if kind == "held":
            held = str(rng.choice(["left", "both"]))
            direction = OUT_OF_PLANE
            shape += f" held {held}"
    name = f"w{seed:03d} {kind} {'in' if direction == IN_PLANE else 'out'} {shape}"
    describe = {
        "kind": kind,
        "plane": "in" if direction == IN_PLANE else "out",
        "friction": round(friction, 3),
        "kt/kn": round(ratio, 3),
        "kn": float(f"{kn:.3g}"),
    }

    def build() -> Model:
        return _on_base(blocks, material, direction, held, name=name)

    return CorpusWall(name, "generated", build, describe)


def generated_walls(count: int = 200, first_seed: int = 0) -> Iterator[CorpusWall]:
    """``count`` walls of :func:`random_wall`, seeds ``first_seed`` onwards."""
    for seed in range(first_seed, first_seed + count):
        yield random_wall(seed)


def corpus(
    groups: tuple[str, ...] = ("validation", "issue", "generated"), count: int = 200
) -> Iterator[CorpusWall]:
    """The walls of the named groups, in that order."""
    if "validation" in groups:
        yield from validation_walls()
    if "issue" in groups:
        yield from issue_walls()
    if "generated" in groups:
        yield from generated_walls(count)
