"""Closed forms a new user checks first, through case files as ``masonry-dem run`` runs them.

The sweep of session 17 (docs/new_user_sweep.md): single blocks tilting at s/a and b/a or
sliding at mu, free walls and columns at t/H and b/H, one course of the plans at s/a, notched
walls at the least over the bed joints of (s/2)/(y_G(z) - z), pressure and point loads,
scale (millimetre blocks, a 10 m wall, kn 1e5-1e14, friction 0.1-100, alpha 1-4). Prints
expected, got, the error in %, the status, the certificate and the limit-analysis bound.

    PYTHONPATH=src python benchmarks/new_user_closed_forms.py [block slide wall plans opening scale loads]
"""

from __future__ import annotations

import copy
import tempfile
import time

import numpy as np
from _machine import arguments, print_machine

from masonry_dem.cases.casefile import case_from_dict
from masonry_dem.run_case import run_case


def case(builder, geo, material=None, supports=None, loads=None, analysis=None):
    d = {
        "name": "t",
        "geometry": {"builder": builder, "unit_weight": 20e3, "base": True, **geo},
        "material": {"kn": 1e9, "kt": 0.4e9, "friction": 0.7, **(material or {})},
        "supports": supports or [{"select": "base"}],
        "loads": loads
        or [{"type": "self_weight"}, {"type": "weight_proportional", "direction": [0, 0, 1]}],
    }
    if analysis:
        d["analysis"] = analysis
    return d


def run(label, data, expected, render=False):
    t = time.perf_counter()
    try:
        c = case_from_dict(copy.deepcopy(data), label)
        with tempfile.TemporaryDirectory() as out:
            s = run_case(c, out, overwrite=True, render=render)
        lam = s["lambda"]
        err = (lam / expected - 1) * 100 if expected else float("nan")
        cert = s.get("certificate") or {}
        print(
            f"{label:45s} exp {expected:.5g} got {lam:.5g} ({err:+.2f} %) {s['status']} "
            f"cert={cert.get('holds')} bound={s.get('limit_analysis_bound')} steps={s['steps']} "
            f"{time.perf_counter() - t:.1f}s",
            flush=True,
        )
        if s["status"] != "collapse":
            print("    reason:", s.get("reason"))
        return s
    except Exception as e:  # noqa: BLE001 - a sweep prints every outcome
        print(f"{label:45s} EXC {type(e).__name__}: {e}", flush=True)


if __name__ == "__main__":
    parser = arguments(__doc__)
    parser.add_argument(
        "groups", nargs="*", metavar="GROUP", help="block slide wall plans opening scale loads"
    )
    which = parser.parse_args().groups
    print_machine()

    def g(a, b, s):
        return dict(block_height=a, block_length=b, thickness=s)

    if not which or "block" in which:
        for a, b, s in [
            (0.1, 0.2, 0.1),
            (0.2, 0.2, 0.1),
            (0.4, 0.2, 0.1),
            (0.8, 0.3, 0.1),
            (0.05, 0.3, 0.2),
        ]:
            run(
                f"block a={a} b={b} s={s} out of plane",
                case("single_block", g(a, b, s)),
                min(0.7, s / a),
            )
            run(
                f"block a={a} b={b} s={s} in plane",
                case(
                    "single_block",
                    g(a, b, s),
                    loads=[
                        {"type": "self_weight"},
                        {"type": "weight_proportional", "direction": [1, 0, 0]},
                    ],
                ),
                min(0.7, b / a),
            )
            run(
                f"block a={a} b={b} s={s} -e3",
                case(
                    "single_block",
                    g(a, b, s),
                    loads=[
                        {"type": "self_weight"},
                        {"type": "weight_proportional", "direction": [0, 0, -1]},
                    ],
                ),
                min(0.7, s / a),
            )
    if not which or "slide" in which:
        for mu in [0.1, 0.3, 0.5, 0.9]:
            a, b, s = 0.1, 0.3, 0.2  # s/a = 2, b/a = 3
            run(
                f"block slides mu={mu} out of plane",
                case("single_block", g(a, b, s), {"friction": mu}),
                mu,
            )
            run(
                f"block slides mu={mu} in plane",
                case(
                    "single_block",
                    g(a, b, s),
                    {"friction": mu},
                    loads=[
                        {"type": "self_weight"},
                        {"type": "weight_proportional", "direction": [1, 0, 0]},
                    ],
                ),
                mu,
            )
    if not which or "wall" in which:
        for n, courses in [(1, 3), (3, 5), (4, 8), (2, 13)]:
            a, b, s = 0.081, 0.21, 0.07
            run(
                f"free wall {n}x{courses} t/H",
                case(
                    "running_bond_wall", dict(blocks_along_length=n, courses=courses, **g(a, b, s))
                ),
                s / (courses * a),
            )
            run(
                f"stack column {courses} t/H",
                case("stack_bond_column", dict(courses=courses, **g(a, b, s))),
                s / (courses * a),
            )
            run(
                f"stack column {courses} in plane b/H",
                case(
                    "stack_bond_column",
                    dict(courses=courses, **g(a, b, s)),
                    loads=[
                        {"type": "self_weight"},
                        {"type": "weight_proportional", "direction": [1, 0, 0]},
                    ],
                ),
                b / (courses * a),
            )
    if not which or "plans" in which:
        a, b, s = 0.2, 0.21, 0.07  # s/a = 0.35 < mu
        for builder, extra in [
            ("l_wall", {"return_blocks": 2}),
            ("u_wall", {"return_blocks": 2}),
            ("t_wall", {"return_blocks": 2}),
            ("box_wall", {}),
        ]:
            geo = dict(blocks_along_length=4, courses=1, **g(a, b, s), **extra)
            run(f"{builder} 1 course e3", case(builder, geo), s / a)
            run(
                f"{builder} 1 course e1",
                case(
                    builder,
                    geo,
                    loads=[
                        {"type": "self_weight"},
                        {"type": "weight_proportional", "direction": [1, 0, 0]},
                    ],
                ),
                s / a,
            )
            geo3 = dict(geo, courses=3, block_height=0.081)
            run(f"{builder} 3 courses e3 (vs LA bound)", case(builder, geo3), float("nan"))
    if not which or "opening" in which:
        from masonry_dem.geometry import builders

        a, b, s = 0.081, 0.21, 0.07
        for n, nc, op in [
            (6, 10, [0.42, 0.567, 0.84, 0.9]),
            (5, 9, [0.2, 0.4, 0.64, 0.8]),
            (6, 10, [0.42, 0.243, 0.84, 0.567]),
        ]:
            geo = dict(blocks_along_length=n, courses=nc, **g(a, b, s), openings=[op])
            bl = builders.cut_openings(builders.running_bond_wall(n, nc, a, b, s, 20e3), [op])
            w = bl.volumes if hasattr(bl, "volumes") else np.prod(bl.sizes, axis=1)
            yc = bl.centres[:, 1]
            cands = []
            for k in range(nc):
                z = k * a
                above = yc > z
                zb = np.sum(w[above] * yc[above]) / np.sum(w[above])
                cands.append(s / (2 * (zb - z)))
            run(
                f"wall {n}x{nc} opening {op} (min over bed joints)",
                case("running_bond_wall", geo),
                min(cands),
            )
    if not which or "scale" in which:
        # millimetre-sized blocks (a model at 1:40), a 10 m wall, kn and friction ranges, alpha
        a, b, s = 0.002, 0.005, 0.0017
        run(
            "mm blocks free wall 3x5 t/H",
            case("running_bond_wall", dict(blocks_along_length=3, courses=5, **g(a, b, s))),
            s / (5 * a),
        )
        run("mm single block s/a", case("single_block", g(a, b, s)), s / a)
        a, b, s = 0.25, 0.5, 0.3
        run(
            "10 m wall 3x40 t/H",
            case("running_bond_wall", dict(blocks_along_length=3, courses=40, **g(a, b, s))),
            s / (40 * a),
        )
        run(
            "10 m stack column 40 t/H",
            case("stack_bond_column", dict(courses=40, **g(a, b, s))),
            s / (40 * a),
        )
        a, b, s = 0.081, 0.21, 0.07
        for kn in [1e5, 1e6, 1e8, 1e10, 1e12, 1e14]:
            run(
                f"free wall 2x6 kn={kn:g} kt=0.4kn",
                case(
                    "running_bond_wall",
                    dict(blocks_along_length=2, courses=6, **g(a, b, s)),
                    {"kn": kn, "kt": 0.4 * kn},
                ),
                s / (6 * a),
            )
            run(
                f"10 m column 40 kn={kn:g}",
                case(
                    "stack_bond_column",
                    dict(courses=40, **g(0.25, 0.5, 0.3)),
                    {"kn": kn, "kt": 0.4 * kn},
                ),
                0.3 / 10,
            )
        for mu in [0.1, 100.0]:
            run(
                f"free wall 2x6 friction={mu}",
                case(
                    "running_bond_wall",
                    dict(blocks_along_length=2, courses=6, **g(a, b, s)),
                    {"friction": mu},
                ),
                min(mu, s / (6 * a)),
            )
            run(
                f"squat block friction={mu}",
                case("single_block", g(0.1, 0.3, 0.2), {"friction": mu}),
                min(mu, 2.0),
            )
        for alpha in [1.0, 1.5, 2.0, 3.0, 4.0]:
            run(
                f"free wall 2x6 alpha={alpha}",
                case(
                    "running_bond_wall",
                    dict(blocks_along_length=2, courses=6, **g(a, b, s)),
                    {"alpha": alpha},
                ),
                s / (6 * a),
            )
            run(
                f"squat block slides alpha={alpha} mu=0.3",
                case("single_block", g(0.1, 0.3, 0.2), {"alpha": alpha, "friction": 0.3}),
                0.3,
            )
    if not which or "loads" in which:
        a, b, s, gam = 0.081, 0.21, 0.07, 20e3
        for n, nc in [(3, 5), (2, 10)]:
            H = nc * a
            p0 = 100.0
            run(
                f"free wall {n}x{nc} pressure value=100",
                case(
                    "running_bond_wall",
                    dict(blocks_along_length=n, courses=nc, **g(a, b, s)),
                    loads=[
                        {"type": "self_weight"},
                        {"type": "pressure", "value": p0, "axis": 2, "sign": 1},
                    ],
                ),
                gam * s * s / (H * p0),
            )
            run(
                f"free wall {n}x{nc} pressure sign -1",
                case(
                    "running_bond_wall",
                    dict(blocks_along_length=n, courses=nc, **g(a, b, s)),
                    loads=[
                        {"type": "self_weight"},
                        {"type": "pressure", "value": p0, "axis": 2, "sign": -1},
                    ],
                ),
                gam * s * s / (H * p0),
            )
            W = gam * s * H * n * b
            # a live point load on the top course, at the top face's centre height? PointLoad acts at block centres (offset 0)
            run(
                f"stack column {nc} point load top (centre)",
                case(
                    "stack_bond_column",
                    dict(courses=nc, **g(a, b, s)),
                    loads=[
                        {"type": "self_weight"},
                        {
                            "type": "point",
                            "select": "course:-1",
                            "force": [0, 0, 1.0],
                            "live": True,
                        },
                    ],
                ),
                (gam * s * a * b * nc) * s / 2 / (H - a / 2),
            )
            run(
                f"column {nc} disp control top u3",
                case(
                    "stack_bond_column",
                    dict(courses=nc, **g(a, b, s)),
                    analysis={
                        "control": {"block": nc - 1, "dof": "u3", "target": 0.02, "steps": 40}
                    },
                ),
                s / H,
            )
        run(
            "wall joint=0.01 4x6 t/H",
            case(
                "running_bond_wall",
                dict(blocks_along_length=4, courses=6, joint=0.01, **g(a, b, s)),
            ),
            s / (6 * (a + 0.01)),
        )
        run(
            "wall start_with_half 4x6 t/H",
            case(
                "running_bond_wall",
                dict(blocks_along_length=4, courses=6, start_with_half=True, **g(a, b, s)),
            ),
            s / (6 * a),
        )
        run(
            "wall_of_size 1.0 x 0.8 t/H",
            case("running_bond_wall_of_size", dict(length=1.0, height=0.8, **g(a, b, s))),
            s / 0.8,
        )
        run(
            "wall origin shifted t/H",
            case(
                "running_bond_wall",
                dict(blocks_along_length=3, courses=5, origin=[5.0, 2.0, -3.0], **g(a, b, s)),
            ),
            s / (5 * a),
        )
        run(
            "tilt direction (0,0,2) (not normalised?)",
            case(
                "running_bond_wall",
                dict(blocks_along_length=3, courses=5, **g(a, b, s)),
                loads=[
                    {"type": "self_weight"},
                    {"type": "weight_proportional", "direction": [0, 0, 2]},
                ],
            ),
            s / (5 * a),
        )
        run(
            "tilt direction (0,-1,1)",
            case(
                "running_bond_wall",
                dict(blocks_along_length=3, courses=5, **g(a, b, s)),
                loads=[
                    {"type": "self_weight"},
                    {"type": "weight_proportional", "direction": [0, -1, 1]},
                ],
            ),
            float("nan"),
        )
        run(
            "tilt direction upward (0,1,0)",
            case(
                "running_bond_wall",
                dict(blocks_along_length=3, courses=5, **g(a, b, s)),
                loads=[
                    {"type": "self_weight"},
                    {"type": "weight_proportional", "direction": [0, 1, 0]},
                ],
            ),
            1.0,
        )
        run(
            "tilt direction down (0,-1,0)",
            case(
                "running_bond_wall",
                dict(blocks_along_length=3, courses=5, **g(a, b, s)),
                loads=[
                    {"type": "self_weight"},
                    {"type": "weight_proportional", "direction": [0, -1, 0]},
                ],
            ),
            float("nan"),
        )
