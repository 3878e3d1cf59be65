"""Benchmark: the validation cases on this tree against an earlier commit, in one run.

Run:  python benchmarks/bench_against_commit.py REF [--cases OL1 S15 ...] [--repeat 2]

Where a machine's speed drifts from one minute to the next, two benchmark runs made apart
cannot be compared. This one checks REF (any commit, tag or branch) out into a temporary git
worktree and runs each case on both trees in turn, each in a fresh process (so each tree
loads its own compiled kernels), ``--repeat`` times per process, keeping the fastest. It
prints per case the wall-clock seconds (the compiled kernels run on every core, so CPU time
would count each thread), factorizations and lambda of both trees and the ratio, and the
totals. Factorizations and Newton iterations are exact; seconds carry the noise of the
machine. With ``NUMBA_NUM_THREADS=1`` the CPU seconds of the process count one thread; their
ratio (``cpu ratio``) is the steadier one on a machine that other work keeps busy.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from _machine import arguments, print_machine

ROOT = Path(__file__).resolve().parents[1]

# run in the child process, with PYTHONPATH on the tree to measure
_CHILD = """
import json, sys, time
from masonry_dem.cases.paper import build_case
try:
    from masonry_dem.studies.runs import warm_up
except ImportError:  # a tree from before the studies left the command line
    from masonry_dem.cli.study import warm_up
from masonry_dem.solvers.incremental import pushover
warm_up()
case = build_case(sys.argv[1])
best = cpu = None
for _ in range(int(sys.argv[2])):
    t, c = time.perf_counter(), time.process_time()
    h = pushover(case.model, case.settings, monitor=case.monitor)
    best = min(best or float("inf"), time.perf_counter() - t)
    cpu = min(cpu or float("inf"), time.process_time() - c)
print(json.dumps(dict(lam=h.collapse_multiplier, fac=h.factorizations, its=h.iterations,
                      s=best, cpu=cpu)))
"""


def _run(src: Path, case: str, repeat: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src))
    # the same thread wait policy for both trees (older ones set it on import, newer ones at
    # their entry points: masonry_dem.set_thread_wait_policy)
    env.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    out = subprocess.run(
        [sys.executable, "-c", _CHILD, case, str(repeat)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> int:
    p = arguments(__doc__)
    p.add_argument("ref", help="the commit to compare with (hash, tag or branch)")
    p.add_argument("--cases", nargs="+", default=None, help="default: every validation case")
    p.add_argument("--repeat", type=int, default=2, help="runs per process, the fastest kept")
    args = p.parse_args()
    print_machine()
    if args.repeat < 1:
        p.error(f"--repeat must be at least 1, got {args.repeat}")
    from masonry_dem.cases.paper import case_names

    cases = args.cases or case_names()
    with tempfile.TemporaryDirectory() as tmp:
        worktree = Path(tmp) / "ref"
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(worktree), args.ref],
            check=True,
        )
        try:
            trees = {args.ref[:10]: worktree / "src", "this tree": ROOT / "src"}
            total = {name: [0.0, 0, 0, 0.0] for name in trees}
            print(
                f"{'case':6} "
                + " | ".join(f"{n:>10} s  fac    lambda" for n in trees)
                + " | ratio | cpu ratio"
            )
            for case in cases:
                rows = {name: _run(src, case, args.repeat) for name, src in trees.items()}
                for name, r in rows.items():
                    total[name][0] += r["s"]
                    total[name][1] += r["fac"]
                    total[name][2] += r["its"]
                    total[name][3] += r["cpu"]
                (old, new) = rows.values()
                print(
                    f"{case:6} "
                    + " | ".join(
                        f"{r['s']:12.2f} {r['fac']:4d} {r['lam']:9.6g}" for r in rows.values()
                    )
                    + f" | {old['s'] / new['s']:.2f}x | {old['cpu'] / new['cpu']:.2f}x",
                    flush=True,
                )
            (old_t, new_t) = total.values()
            for name, (s, fac, its, cpu) in total.items():
                print(
                    f"{name}: {s:.1f} s ({cpu:.1f} s CPU), {fac} factorizations, {its} iterations"
                )
            print(f"ratio: {old_t[0] / new_t[0]:.2f}x, CPU {old_t[3] / new_t[3]:.2f}x")
        finally:
            subprocess.run(
                ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(worktree)],
                check=False,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
