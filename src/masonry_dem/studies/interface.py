"""The interface-strength study: the closed-form shear and torsion strengths of one interface
against its spring model, the convergence of the spring model's torsion strength with the
springs per side, and Table A1 (alpha fitted to spring-model domains) beside the published
values."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from masonry_dem.constitutive import (
    ALPHA_TABLE_A1,
    REFERENCE_INTERFACE,
    fit_alpha,
    shear_strength,
    shear_strength_numeric,
    torsion_constant,
    torsion_strength,
    torsion_strength_numeric,
)
from masonry_dem.model import check_tension_cap

#: springs per side of the torsion-convergence table (n = 64 is 4096 springs, a few ms)
CONVERGENCE_N = (4, 8, 16, 32, 64)


@dataclass(frozen=True)
class Interface:
    """One rectangular interface: sides l1, l2 [m], normal force [N] (< 0: compression),
    friction coefficient, tensile strength [Pa], stiffnesses [N/m^3], springs per side of its
    spring model and cohesion [Pa] (None: mu ft, the paper's reading; at least mu ft). The
    default: Section 2.1 of the paper."""

    l1: float = REFERENCE_INTERFACE.l1
    l2: float = REFERENCE_INTERFACE.l2
    normal_force: float = REFERENCE_INTERFACE.normal_force
    friction: float = REFERENCE_INTERFACE.friction
    tensile_strength: float = 0.0
    kn: float = REFERENCE_INTERFACE.kn
    ks: float = REFERENCE_INTERFACE.ks
    springs_per_side: int = REFERENCE_INTERFACE.n
    cohesion: float | None = None


def interface_study(
    it: Interface, directions: int = 16, alpha_n: int = 32, alpha_table: bool = True
) -> dict[str, Any]:
    """All figures as a JSON-ready dict: ``directions`` shear directions checked in the
    plane; the alpha fits with ``alpha_n`` springs per side (21 fits: about a second)."""
    if directions < 1:
        raise ValueError(f"directions must be >= 1, got {directions}")
    l1, l2, fn, mu, ts = it.l1, it.l2, it.normal_force, it.friction, it.tensile_strength
    if it.cohesion is not None:  # named in Pa, as the material names it
        check_tension_cap(mu, ts, it.cohesion)
    ft = ts * l1 * l2
    c, ca = it.cohesion, None if it.cohesion is None else it.cohesion * l1 * l2
    fsu = float(shear_strength(fn, mu, ft, ca))
    m3u = float(torsion_strength(fn, l1, l2, mu, ft, cohesive_force=ca))
    n, kn, ks = it.springs_per_side, it.kn, it.ks
    angles = np.linspace(0.0, 2.0 * np.pi, directions, endpoint=False)
    fs = shear_strength_numeric(l1, l2, fn, mu, ts, angles=angles, n=n, kn=kn, ks=ks, cohesion=c)
    m3s = torsion_strength_numeric(l1, l2, fn, mu, ts, n=n, kn=kn, ks=ks, cohesion=c)
    out: dict[str, Any] = {
        "interface": {k: v for k, v in asdict(it).items()},
        "torsion_constant": float(torsion_constant(l1, l2)),
        "shear_strength": fsu,
        "torsion_strength": m3u,
        "spring_shear_strength": float(fs.min()),
        "spring_shear_strength_max": float(fs.max()),
        "spring_shear_directions": len(angles),
        "spring_torsion_strength": m3s,
        "torsion_convergence": [],
        "alpha_table": [],
    }
    for side in CONVERGENCE_N:
        value = torsion_strength_numeric(l1, l2, fn, mu, ts, n=side, kn=kn, ks=ks, cohesion=c)
        out["torsion_convergence"].append(
            {"n": side, "spring_torsion_strength": value, "relative_error": value / m3u - 1.0}
        )
    if alpha_table:
        out["alpha_springs_per_side"] = alpha_n
        for direction in [k for k in ALPHA_TABLE_A1 if k != "aspect"]:  # its columns
            for aspect, paper in zip(
                ALPHA_TABLE_A1["aspect"], ALPHA_TABLE_A1[direction], strict=True
            ):
                out["alpha_table"].append(
                    {
                        "aspect": aspect,
                        "direction": direction,
                        "alpha_fitted": round(fit_alpha(aspect, direction, n=alpha_n), 4),
                        "alpha_paper": paper,
                    }
                )
    return out


def _pct(value: float, ref: float) -> str:
    if not ref:
        return "n/a"
    pct = 100.0 * (value / ref - 1.0)
    return f"{0.0 if abs(pct) < 5e-4 else pct:+.3f} %"  # no "-0.000 %"


def interface_text(res: dict[str, Any]) -> str:
    """The study as the ``masonry-dem interface`` command prints it."""
    i = res["interface"]
    n = i["springs_per_side"]
    lines = [
        f"Interface {i['l1']:.3f} x {i['l2']:.3f} m, fn = {i['normal_force']:g} N, "
        f"mu = {i['friction']:g}, tensile strength = {i['tensile_strength']:g} Pa, "
        + (
            "cohesion = mu ft, "
            if i.get("cohesion") is None
            else f"cohesion = {i['cohesion']:g} Pa, "
        )
        + f"{n} x {n} springs",
        f"torsion constant cT = {res['torsion_constant']:.5f} m",
        f"{'':24s}{'closed form':>14s}{'spring model':>14s}{'difference':>14s}",
    ]
    fsu, fmin = res["shear_strength"], res["spring_shear_strength"]
    fmax = res["spring_shear_strength_max"]
    lines.append(f"{'shear strength [N]':24s}{fsu:14.3f}{fmin:14.3f}{_pct(fmin, fsu):>14s}")
    lines.append(
        f"{'':24s}{'':14s}{fmax:14.3f}{_pct(fmax, fsu):>14s}"
        f"  (min, max over {res['spring_shear_directions']} directions)"
    )
    m3u, m3s = res["torsion_strength"], res["spring_torsion_strength"]
    lines.append(f"{'torsion strength [N m]':24s}{m3u:14.3f}{m3s:14.3f}{_pct(m3s, m3u):>14s}")
    lines.append("\nspring-model torsion strength against the closed form, n x n springs")
    lines.append(f"{'n':>5s}{'m3u spring [N m]':>18s}{'error':>12s}")
    for row in res["torsion_convergence"]:
        err = 100.0 * row["relative_error"]
        lines.append(f"{row['n']:5d}{row['spring_torsion_strength']:18.4f}{err:+11.3f}%")
    if res["alpha_table"]:
        na = res["alpha_springs_per_side"]
        lines.append(f"\nTable A1: alpha fitted to the spring-model domain ({na} x {na} springs)")
        lines.append(f"{'l1/l2':>7s}  {'direction':9s}{'fitted':>8s}{'paper':>8s}{'diff':>8s}")
        for row in res["alpha_table"]:
            diff = row["alpha_fitted"] - row["alpha_paper"]
            lines.append(
                f"{row['aspect']:7.1f}  {row['direction']:9s}{row['alpha_fitted']:8.3f}"
                f"{row['alpha_paper']:8.2f}{diff:+8.3f}"
            )
        lines.append("('f1=f2': the paper's loading with equal relative displacements d1 = d2)")
    return "\n".join(lines)
