"""Benchmark: a sweep of the default wall run serially against a Dask LocalCluster of this machine.

Benchmark: a sweep of the default wall run serially in this process against the same sweep
on a Dask LocalCluster of this machine, in one run, with the scheduler's overhead per task.

Run:  python benchmarks/bench_sweep.py [--runs 100] [--workers N]

The runs vary the friction of the bundled default wall over 0.5:0.9 (``--runs`` values), so
every run is a whole analysis (limit-analysis bound, pushover, mechanism summary). Printed:

* serial: the runs one after the other in this process (``run_point``, as a worker calls it),
  after one warm-up run that loads the compiled kernels;
* cluster: ``masonry_dem.sweep`` on a LocalCluster of ``--workers`` processes (default: the
  cores), split into the cluster's start-up and the sweep itself (which includes each
  worker's first import of the package and its kernels, the table and the plot);
* the speed-up serial / cluster (with and without the start-up);
* the scheduler's overhead per task: ``workers x sweep seconds - sum of the runs' own
  seconds``, per run (what the cluster costs beyond the analyses: scheduling, transfer,
  the workers' first imports, idle workers at the end), and the round trip of a task that
  does nothing, from 1000 of them.

Each figure is from this one run: the ratios hold for this machine at its present load (see
``uptime``), not for another.
"""

from __future__ import annotations

import os
import platform
import tempfile
import time

import numpy as np
from _machine import arguments, print_machine

from masonry_dem.studies.sweep import make_plan, run_point, sweep


def _noop(i: int) -> int:
    return i


def main() -> int:
    p = arguments(__doc__)
    p.add_argument("--runs", type=int, default=100, help="runs of the default wall")
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="cluster processes")
    args = p.parse_args()
    print_machine()
    if args.runs < 2 or args.workers < 1:
        p.error("--runs must be at least 2 and --workers at least 1")
    from distributed import Client, LocalCluster

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"python {platform.python_version()} on {platform.machine()}, {os.cpu_count()} cores, "
        f"load average {load:.2f}, {time.ctime()}"
    )
    vary = {"material.friction": f"0.5:0.9:{args.runs}"}
    plan = make_plan(None, vary=vary)
    points = plan.points()

    run_point(plan.case_of(points[0]), plan.source)  # the kernels loaded before timing
    t0 = time.perf_counter()
    serial = [run_point(plan.case_of(pt), plan.source) for pt in points]
    t_serial = time.perf_counter() - t0

    t0 = time.perf_counter()
    with (
        LocalCluster(
            n_workers=args.workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",
            env={"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"},
        ) as cluster,
        Client(cluster) as client,
    ):
        t_start = time.perf_counter() - t0
        with tempfile.TemporaryDirectory() as out:
            t0 = time.perf_counter()
            result = sweep(None, vary=vary, out=out, scheduler=client)
            t_sweep = time.perf_counter() - t0
        t0 = time.perf_counter()
        client.gather(client.map(_noop, range(1000), pure=False))
        t_noop = (time.perf_counter() - t0) / 1000

    same = all(
        a["lambda"] == b["lambda"] and a["status"] == b["status"]
        for a, b in zip(serial, result.rows, strict=True)
    )
    busy = float(np.sum([r["seconds"] for r in result.rows]))
    cpu_cluster = float(np.sum([r["cpu_seconds"] for r in result.rows]))
    cpu_serial = float(np.sum([r["cpu_seconds"] for r in serial]))
    overhead = (args.workers * t_sweep - busy) / args.runs
    statuses = sorted({r["status"] for r in result.rows})
    print(f"{args.runs} runs of the default wall, friction 0.5:0.9, statuses {statuses}")
    print(f"serial, this process:        {t_serial:8.2f} s  ({t_serial / args.runs:.3f} s a run)")
    print(f"cluster start-up:            {t_start:8.2f} s  ({args.workers} worker processes)")
    print(f"cluster sweep:               {t_sweep:8.2f} s  (runs' own seconds: {busy:.2f})")
    print(
        f"speed-up serial / cluster:   {t_serial / t_sweep:8.2f}x without start-up, "
        f"{t_serial / (t_sweep + t_start):.2f}x with it"
    )
    print(
        f"CPU seconds of the runs:     {cpu_serial:8.2f} s serial, {cpu_cluster:.2f} s on the "
        "workers (wall / CPU above 1: waiting for a core)"
    )
    print(
        f"CPU share:                   {cpu_serial / t_serial:8.2f} cores serial, "
        f"{cpu_cluster / t_sweep:.2f} for the workers together"
    )
    print(f"overhead per run:            {1e3 * overhead:8.1f} ms  (workers x sweep - runs' own)")
    print(f"no-op task round trip:       {1e3 * t_noop:8.2f} ms  (1000 tasks)")
    print(f"lambda of every run equal serial and cluster: {same}")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
