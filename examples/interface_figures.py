"""Figures 5, 7, 8, 9, 10, A1 and A4 of Baraldi & Cecchi from the spring model of one interface.

Every figure is computed with the spring (fibre) model of Section 2.1
(:class:`masonry_dem.constitutive.SpringInterface`) and the closed-form strength domain
(:mod:`masonry_dem.constitutive.strength`) is drawn over it (dashed lines).

    python examples/interface_figures.py [--out results/interface_figures] [--quick]

``--quick`` uses 8 x 8 springs and fewer analyses (the test suite runs it); the default is the
paper's 32 x 32 springs and takes a few seconds.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
matplotlib.rcParams["axes.formatter.useoffset"] = False  # every tick its own value
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from masonry_dem.constitutive import (  # noqa: E402
    ALPHA_TABLE_A1,
    REFERENCE_INTERFACE,
    SpringInterface,
    fit_alpha,
    shear_strength,
    torsion_shear_domain,
    torsion_strength,
    torsion_strength_numeric,
)

log = logging.getLogger("interface_figures")

REF = REFERENCE_INTERFACE
L1, L2, FN, MU = REF.l1, REF.l2, REF.normal_force, REF.friction
ASPECTS = ALPHA_TABLE_A1["aspect"]


def _iface(n: int, tensile_strength: float = 0.0) -> SpringInterface:
    return SpringInterface(L1, L2, n, REF.kn, REF.ks, MU, tensile_strength)


def _curve(alpha: float, points: int = 200) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) on (x)^alpha + y^2 = 1, x = m3/m3u, y = f/fsu."""
    y = np.linspace(0.0, 1.0, points)
    return np.clip(1.0 - y**2, 0.0, None) ** (1.0 / alpha), y


def figure_5(out: Path, n: int, steps: int) -> Path:
    """Shear force against relative displacement along y1 and y2; the (f1, f2) domain."""
    iface = _iface(n)
    fsu = float(shear_strength(FN, MU))
    u_y = iface.yield_slip(FN)
    d = np.linspace(0.0, 5.0 * u_y, steps)
    paths = np.zeros((2, steps, 6))
    paths[0, :, 0] = d
    paths[1, :, 1] = d
    curves = iface.run(paths, normal_force=FN).actions
    angles = np.linspace(0.0, 2.0 * np.pi, 36, endpoint=False)
    dirs = np.zeros((angles.size, steps, 6))
    dirs[:, :, 0] = np.cos(angles)[:, None] * d
    dirs[:, :, 1] = np.sin(angles)[:, None] * d
    ult = iface.run(dirs, normal_force=FN).ultimate

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4.2))
    a.plot(d * 1e3, curves[0, :, 0], label="$f_1$ ($d_1$ only)")
    a.plot(d * 1e3, curves[1, :, 1], "--", label="$f_2$ ($d_2$ only)")
    a.axhline(fsu, color="k", ls=":", lw=1, label=r"$f_{s,u} = -\mu f_3$")
    a.set(xlabel="relative displacement [mm]", ylabel="shear force [N]")
    a.legend()
    t = np.linspace(0, 2 * np.pi, 200)
    b.plot(ult[:, 0], ult[:, 1], "o", ms=4, label=f"spring model ({n}x{n})")
    b.plot(fsu * np.cos(t), fsu * np.sin(t), "k--", lw=1, label="Eq. (10)")
    b.set(xlabel="$f_1$ [N]", ylabel="$f_2$ [N]", aspect="equal")
    b.legend(loc="center")
    fig.suptitle("Figure 5: shear strength in the plane of the interface")
    return _save(fig, out / "figure_5_shear.png")


def figure_7(out: Path, n: int) -> Path:
    """Shear stress lines: pure torsion and torsion with shear f1."""
    iface = _iface(n)
    paths = iface.rotation_paths(0.0, np.array([0.0, 0.2 * np.pi]), FN, steps=2)
    res = iface.run(paths, normal_force=FN)
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    for ax, k, title in zip(axes, (0, 1), ("pure torsion", "torsion and shear $f_1$"), strict=True):
        tau = res.spring_shear[k, -1]
        c = res.centres
        ax.quiver(c[:, 0], c[:, 1], tau[:, 0], tau[:, 1], pivot="mid", scale_units="xy")
        ax.set(title=title, xlabel="$y_1$ [m]", ylabel="$y_2$ [m]", aspect="equal")
    fig.suptitle("Figure 7: shear stresses at the ultimate state")
    return _save(fig, out / "figure_7_stress_lines.png")


def figure_8(out: Path, n: int, steps: int, paths_count: int) -> Path:
    """Incremental shear-torsion analyses and the m3-f1 domain of the reference interface."""
    iface = _iface(n)
    theta = np.linspace(0.0, 0.5 * np.pi, paths_count)
    # curves: the same proportional paths, shortened so that the farthest spring slips 30
    # times its yield slip, to show the elastic branch and the spread of plasticity
    paths = iface.rotation_paths(0.0, theta, FN, steps)
    end = paths[:, -1, :]
    c1, c2 = iface.centres.T
    far = np.hypot(end[:, :1] - end[:, 5:] * c2, end[:, 1:2] + end[:, 5:] * c1).max(axis=1)
    paths *= (30.0 * iface.yield_slip(FN) / far)[:, None, None]
    res = iface.run(paths, normal_force=FN)
    x, y = torsion_shear_domain(L1 / L2, "f1", n=n, points=max(paths_count, 12))
    fsu = float(shear_strength(FN, MU))
    m3u = float(torsion_strength(FN, L1, L2, MU))
    alpha = fit_alpha(L1 / L2, "f1", n=n)

    fig, (a, b, c) = plt.subplots(1, 3, figsize=(14, 4.2))
    for k in range(theta.size):
        a.plot(res.displacements[k, :, 0] * 1e3, res.actions[k, :, 0])
        b.plot(res.displacements[k, :, 5] * 1e3, res.actions[k, :, 5])
    a.set(xlabel="$d_1$ [mm]", ylabel="$f_1$ [N]", title="shear force")
    b.set(xlabel=r"$\delta_3$ [mrad]", ylabel="$m_3$ [N m]", title="torsion")
    c.plot(y * fsu, x * m3u, "o", ms=4, label=f"spring model ({n}x{n})")
    xc, yc = _curve(2.0)
    c.plot(yc * fsu, xc * m3u, "k--", lw=1, label="circle")
    xa, ya = _curve(alpha)
    c.plot(ya * fsu, xa * m3u, "r-", lw=1, label=rf"Eq. (A4), fitted $\alpha$ = {alpha:.2f}")
    c.set(xlabel="$f_1$ [N]", ylabel="$m_3$ [N m]", title=r"$m_3$-$f_1$ domain")
    c.legend()
    fig.suptitle(f"Figure 8: torsion and shear, {L1} x {L2} m interface, $f_3$ = {FN} N")
    return _save(fig, out / "figure_8_torsion_shear.png")


def _domains(n: int, points: int) -> dict[float, tuple[np.ndarray, np.ndarray]]:
    return {a: torsion_shear_domain(a, "f1", n=n, points=points) for a in ASPECTS}


def figure_9(out: Path, domains: dict) -> Path:
    """Dimensionless m3-f1 domains for l1/l2 from 0.1 to 10."""
    fig, ax = plt.subplots(figsize=(6, 5))
    for aspect, (x, y) in domains.items():
        ax.plot(y, x, "o-", ms=3, lw=1, label=f"$l_1/l_2$ = {aspect:g}")
    ax.set(xlabel=r"$f_1/f_{s,u}$", ylabel=r"$m_3/m_{3,u}$", xlim=(0, 1.02), ylim=(0, 1.02))
    ax.legend(fontsize=8)
    ax.set_title("Figure 9: torsion-shear domains (spring model)")
    return _save(fig, out / "figure_9_domains.png")


def figure_a4(out: Path, domains: dict, n: int) -> Path:
    """Each domain of Figure 9 with Eq. (A4): the paper's alpha and the fitted one."""
    fig, axes = plt.subplots(2, 4, figsize=(15, 7.5))
    for ax, (aspect, (x, y)), paper in zip(
        axes.flat, domains.items(), ALPHA_TABLE_A1["f1"], strict=False
    ):
        fitted = fit_alpha(aspect, "f1", n=n)
        ax.plot(y, x, "o", ms=3, label="spring model")
        xp, yp = _curve(paper)
        ax.plot(yp, xp, "k--", lw=1, label=rf"paper $\alpha$ = {paper:.2f}")
        xf, yf = _curve(fitted)
        ax.plot(yf, xf, "r-", lw=1, label=rf"fitted $\alpha$ = {fitted:.2f}")
        ax.set(title=f"$l_1/l_2$ = {aspect:g}", xlim=(0, 1.02), ylim=(0, 1.02))
        ax.set(xlabel=r"$f_1/f_{s,u}$", ylabel=r"$m_3/m_{3,u}$")
        ax.legend(fontsize=7)
    axes.flat[-1].axis("off")
    fig.suptitle("Figure A4: torsion-shear domains and Eq. (A4)")
    return _save(fig, out / "figure_A4_alpha.png")


def figure_a1(out: Path, n: int, count: int) -> Path:
    """Pure-torsion strength against the tensile strength of the interface."""
    sigma_t = np.linspace(0.0, 0.1e6, count)
    num = [torsion_strength_numeric(L1, L2, FN, MU, s, n=n) for s in sigma_t]
    closed = torsion_strength(FN, L1, L2, MU, sigma_t * L1 * L2)
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.plot(sigma_t / 1e6, num, "-o", ms=4, label=f"spring model ({n}x{n})")
    ax.plot(sigma_t / 1e6, closed, "k--", label="Eq. (12)")
    ax.set(xlabel=r"tensile strength $\bar\sigma_t$ [MPa]", ylabel="$m_{3,u}$ [N m]")
    ax.legend()
    ax.set_title("Figure A1: torsion strength and tensile strength")
    return _save(fig, out / "figure_A1_torsion_tension.png")


def figure_10(out: Path, n: int, count: int) -> Path:
    """Torsion strength reduced by bending (uniform compression on the reduced rectangle)."""
    cap = -FN
    u = np.linspace(0.0, 0.95, count)
    cases = {
        "$m_1$ only": (u * cap * L2 / 2, 0 * u),
        "$m_2$ only": (0 * u, u * cap * L1 / 2),
        "$m_1/m_{1,u} = m_2/m_{2,u}$": (u * cap * L2 / 2, u * cap * L1 / 2),
    }
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for k, (label, (m1, m2)) in enumerate(cases.items()):
        num = [
            torsion_strength_numeric(L1, L2, FN, MU, m1=a, m2=b, n=n)
            for a, b in zip(m1, m2, strict=True)
        ]
        closed = torsion_strength(FN, L1, L2, MU, 0.0, m1, m2)
        ax.plot(u, num, "o", color=f"C{k}", ms=4, label=f"{label}: spring model")
        ax.plot(u, closed, "--", color=f"C{k}", lw=1, label=f"{label}: closed form")
    ax.set(xlabel="bending moment / rocking limit", ylabel="$m_{3,u}$ [N m]")
    ax.legend(fontsize=7)
    ax.set_title("Figure 10: torsion strength and bending moments")
    return _save(fig, out / "figure_10_torsion_bending.png")


#: resolution of the PNGs; --quick lowers it and skips tight_layout (the text layout is what
#: costs time in matplotlib, not the spring model)
_DPI = {"dpi": 110, "tight": True}


def _save(fig: plt.Figure, path: Path) -> Path:
    if _DPI["tight"]:
        fig.tight_layout()
    fig.savefig(path, dpi=_DPI["dpi"])
    plt.close(fig)
    log.info("wrote %s", path)
    return path


def main(argv: list[str] | None = None) -> list[Path]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("results/interface_figures"))
    parser.add_argument("--quick", action="store_true", help="coarse springs, fewer analyses")
    args = parser.parse_args(argv)
    n, steps, count, paths_count = (8, 12, 4, 6) if args.quick else (REF.n, 60, 11, 12)
    _DPI.update({"dpi": 40, "tight": False} if args.quick else {"dpi": 110, "tight": True})
    args.out.mkdir(parents=True, exist_ok=True)
    domains = _domains(n, points=16 if args.quick else 48)
    written = [
        figure_5(args.out, n, steps),
        figure_7(args.out, n if args.quick else 16),
        figure_8(args.out, n, steps, paths_count),
        figure_9(args.out, domains),
        figure_a4(args.out, domains, n),
        figure_a1(args.out, n, count),
        figure_10(args.out, n, count),
    ]
    for path in written:
        print(path)
    return written


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main()
