"""The certificate of every validation case: status, lambda, rho along the load, mode, residual.

The certificate of every validation case: status, lambda, the Rayleigh quotient rho of the
tangent along the motion the load drives (against ``mode_stiffness``), Bergan's stiffness
parameter, the mode, the largest utilisation and the residual of the state checked.

    python benchmarks/certificate_validation.py [CASE ...]
"""

from __future__ import annotations

from _machine import arguments, print_machine

from masonry_dem.cases.paper import build_case, case_names
from masonry_dem.solvers.incremental import StaticSolver


def main(argv: list[str] | None = None) -> None:
    p = arguments(__doc__)
    p.add_argument("cases", nargs="*", metavar="CASE", help="validation cases (default: all)")
    names = p.parse_args(argv).cases or case_names()
    print_machine()
    print(
        f"{'case':6s} {'status':9s} {'lambda':>10s} {'rho':>9s} {'S':>9s} {'mode':44s} util residual"
    )
    for name in names:
        case = build_case(name)
        hist = StaticSolver(case.model, case.settings).run(monitor=case.monitor)
        cert = hist.certificate
        lam = hist.collapse_multiplier if hist.collapse_multiplier is not None else float("nan")
        if cert is None:
            print(f"{name:6s} {hist.status!s:9s} {lam:10.6g} (no certificate: {hist.stop})")
            continue
        print(
            f"{name:6s} {hist.status!s:9s} {lam:10.6g} {cert.mode_rayleigh:9.2e} "
            f"{cert.stiffness_parameter:9.2e} {cert.mode:44s} {cert.utilisation:.6f} "
            f"{cert.residual:.1e}",
            flush=True,
        )


if __name__ == "__main__":
    main()
