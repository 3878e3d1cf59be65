"""The smallest real parts of the eigenvalues of the static tangent along a pushover path.

    python benchmarks/tangent_stability.py S23 [S15 ...]

For each converged state (every fourth, and the last ten), the eigenvalues of the consistent
tangent K_t of the free DOFs, scaled by its elastic diagonal (D^-1/2 K_t D^-1/2, so 1 is the
stiffness of an elastic joint), without the residual floor. A negative real eigenvalue is a
state that the load-controlled dynamics leaves along that mode (dynamic relaxation cannot
settle there). Dense eigenvalues: walls of a few thousand DOFs at most.
"""

from __future__ import annotations

import argparse

import numpy as np

from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.static.certificate import law_state_before
from masonry_dem.solvers.static.problem import TangentAssembler
from masonry_dem.solvers.static.solver import StaticSolver


def smallest_real_eigenvalues(name: str, count: int = 2) -> list[tuple[float, np.ndarray]]:
    """(lambda, the ``count`` smallest real parts) at converged states of the case's path."""
    case = build_case(name)
    solver = StaticSolver(case.model, case.settings)
    history = solver.run()
    asm, law = solver.problem.asm, solver.law
    tangents = TangentAssembler(asm, case.model)
    scale = 1.0 / np.sqrt(asm.stiffness().diagonal())  # the elastic diagonal
    steps = history.steps[1:]
    picked = set(range(0, len(steps), 4)) | set(range(max(0, len(steps) - 10), len(steps)))
    rows = []
    for i, step in enumerate(steps):
        x = step.q.reshape(-1)[asm.free_index]
        # the law state the step was found with (its slip, its cracked joints)
        plastic, cracked = law_state_before(solver.problem, history, i + 1)
        response = law.respond((asm.H_free @ x).reshape(-1, 6), plastic, cracked)
        if i in picked:
            K = tangents.matrix(law.tangent(response, 0.0)).toarray() * scale[:, None] * scale
            rows.append((step.load_factor, np.sort(np.linalg.eigvals(K).real)[:count]))
        cracked = law.cracked_after(cracked, response)  # mortar joints stay cracked
    return rows


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("cases", nargs="+")
    args = p.parse_args()
    for name in args.cases:
        print(f"{name}: lambda, smallest real parts of the scaled tangent's eigenvalues")
        for lam, low in smallest_real_eigenvalues(name):
            print(f"  {lam:12.6g}  " + "  ".join(f"{v: .3e}" for v in low))


if __name__ == "__main__":
    main()
