"""Benchmark: the interface strength check and the spring model against one sparse factorization.

Run:  python benchmarks/bench_constitutive.py [--interfaces 1000000] [--steps 1000] [--n 32]
                                              [--wall-blocks 10000] [--repeat 3]

Prints one table, best of ``--repeat`` runs:

- ``check_strength``: the closed-form domain (Eqs. 9-14, A5, torsion-bending interaction) on
  ``--interfaces`` random trial actions (a mix of elastic, sliding, rocking, detached), and on as
  many interfaces as the wall below has;
- ``spring path``: one ``--n`` x ``--n`` spring interface (1024 springs by default) driven along
  a ``--steps`` load path of cyclic shear, bending and torsion, with the normal force held at
  -240 N (dn solved each step) and with dn imposed;
- ``Table A1 fits``: the 21 alpha fits of ``masonry-dem interface`` (32 x 32 springs);
- ``splu``: one ``scipy.sparse.linalg.splu`` factorization of the stiffness K = H^T Kbar H of a
  running-bond wall of about ``--wall-blocks`` blocks on a fixed base, built with the package's
  own pipeline (``running_bond_wall`` + ``detect_interfaces`` + ``Model`` + ``Assembly``): the
  matrix a panel solver factorizes at every stiffness update.
"""

from __future__ import annotations

import argparse
import platform
import time
from collections.abc import Callable

import numpy as np
from scipy.sparse.linalg import splu

from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.constitutive import (
    ALPHA_TABLE_A1,
    REFERENCE_INTERFACE,
    SpringInterface,
    check_strength,
    fit_alpha,
)
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.geometry.interfaces import detect_interfaces
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support

A, B, S, GAMMA = 0.081, 0.21, 0.07, 20_000.0  # Orduna & Lourenco bricks
MATERIAL = InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=0.7)


def best_of(repeat: int, fn: Callable[[], object]) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def random_actions(m: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    act = rng.normal(size=(m, 6)) * [100.0, 100.0, 200.0, 10.0, 10.0, 10.0]
    act[:, 2] -= 200.0
    return act


def load_path(steps: int) -> np.ndarray:
    t = np.linspace(0.0, 1.0, steps)
    path = np.zeros((steps, 6))
    path[:, 0] = 1e-4 * np.sin(6 * np.pi * t)
    path[:, 1] = 5e-5 * np.sin(4 * np.pi * t)
    path[:, 3] = 2e-3 * np.sin(2 * np.pi * t)
    path[:, 4] = 1e-3 * np.sin(3 * np.pi * t)
    path[:, 5] = 1e-3 * np.sin(5 * np.pi * t)
    return path


def wall_stiffness(n_blocks: int):
    per_course = max(1, round(np.sqrt(n_blocks * A / B)))
    courses = max(1, round(n_blocks / (per_course + 0.5)))
    blocks, base = add_base(running_bond_wall(per_course, courses, A, B, S, GAMMA))
    its = detect_interfaces(blocks)
    model = Model.build(blocks, MATERIAL, [Support([base])], [SelfWeight()], interfaces=its)
    asm = Assembly.of(model)
    return asm.stiffness(), blocks.count, its.count


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--interfaces", type=int, default=1_000_000)
    p.add_argument("--steps", type=int, default=1000)
    p.add_argument("--n", type=int, default=32, help="springs per side")
    p.add_argument("--wall-blocks", type=int, default=10_000)
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args(argv)

    rows: list[tuple[str, str, float, str]] = []

    act = random_actions(args.interfaces)
    t = best_of(args.repeat, lambda: check_strength(act, 0.3, 0.2, 0.7, 0.0))
    states = np.bincount(check_strength(act, 0.3, 0.2, 0.7, 0.0).state, minlength=5)
    rows.append(
        (
            "check_strength",
            f"{args.interfaces:,} interfaces",
            t,
            f"{t / args.interfaces * 1e9:.0f} ns/interface; states {states.tolist()}",
        )
    )

    ref = REFERENCE_INTERFACE
    iface = SpringInterface(ref.l1, ref.l2, args.n, ref.kn, ref.ks, ref.friction)
    path = load_path(args.steps)
    springs = args.n**2
    t = best_of(args.repeat, lambda: iface.run(path, normal_force=ref.normal_force))
    rows.append(
        (
            "spring path, fn held",
            f"{springs} springs x {args.steps} steps",
            t,
            f"{t / (springs * args.steps) * 1e9:.0f} ns/spring-step",
        )
    )
    imposed = path.copy()
    imposed[:, 2] = ref.normal_force / (ref.kn * ref.l1 * ref.l2)
    t = best_of(args.repeat, lambda: iface.run(imposed))
    rows.append(
        (
            "spring path, dn imposed",
            f"{springs} springs x {args.steps} steps",
            t,
            f"{t / (springs * args.steps) * 1e9:.0f} ns/spring-step",
        )
    )

    def fits() -> None:
        for direction in ("f1", "f2", "f1=f2"):
            for aspect in ALPHA_TABLE_A1["aspect"]:
                fit_alpha(aspect, direction, n=32)

    t = best_of(1, fits)
    rows.append(("Table A1 fits", "21 fits, 32 x 32 springs", t, "masonry-dem interface"))

    t0 = time.perf_counter()
    K, n_blocks, n_its = wall_stiffness(args.wall_blocks)
    t_build = time.perf_counter() - t0
    t_lu = best_of(args.repeat, lambda: splu(K))
    lu = splu(K)
    rows.append(
        (
            "splu(K) of a wall",
            f"{n_blocks:,} blocks, {n_its:,} interfaces, {K.shape[0]:,} DOFs",
            t_lu,
            f"nnz(K) {K.nnz:,}, nnz(L+U) {lu.L.nnz + lu.U.nnz:,}; build {t_build:.2f} s",
        )
    )
    act_wall = random_actions(n_its, seed=1)
    t_wall = best_of(args.repeat, lambda: check_strength(act_wall, 0.105, 0.07, 0.7, 0.0))
    rows.append(
        (
            "check_strength, wall size",
            f"{n_its:,} interfaces",
            t_wall,
            f"{t_lu / t_wall:.0f}x faster than splu(K)",
        )
    )

    print(f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}")
    w = max(len(r[0]) for r in rows), max(len(r[1]) for r in rows)
    print(f"{'case':{w[0]}s}  {'size':{w[1]}s}  {'time [s]':>9s}  notes")
    for name, size, t, note in rows:
        print(f"{name:{w[0]}s}  {size:{w[1]}s}  {t:9.4f}  {note}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
