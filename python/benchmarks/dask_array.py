"""One volume across a Dask cluster against one process (issue #44): wall and CPU time of
``slabscope.dask.analyze_array`` on a LocalCluster of process workers and of ``slabscope.analyze``
in this process, on the same voxels, and the per-task figures a model of the scaling is made from.

    SLABSCOPE_BIN=target/release/slabscope python python/benchmarks/dask_array.py \\
        --size 512 --chunk 64 --workers 2 --params paper --params defaults

The volume is the CLI's CT-like body phantom (``slabscope phantom body``), written once as a Zarr
array of ``--chunk``³ chunks in ``--folder`` (indexed [z, y, x]). The single process reads that
store into memory and analyses it; the cluster reads it chunk by chunk in its tasks. CPU time is
the client's (with the scheduler, which a LocalCluster runs in the client's process) and every
worker process's (``getrusage``), so that a shared machine's load does not hide the cost of the
split; the client's alone is given too. Prints one JSON object a run."""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import tempfile
import time
from collections import defaultdict

import numpy as np

PARAMS = {"paper": {"phases": 0, "background": "none"}, "defaults": {}}


def cpu() -> float:
    """This process's CPU time, s (user and system)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def store(folder: str, size: int, chunk: int) -> str:
    import zarr

    import slabscope

    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, f"body{size}_c{chunk}.zarr")
    if os.path.exists(path):
        return path
    binary = os.environ.get("SLABSCOPE_BIN") or shutil.which("slabscope") or "target/release/slabscope"
    nii = os.path.join(folder, f"body{size}.nii")
    subprocess.run([binary, "phantom", "body", "--dims", f"{size}x{size}x{size}", "-o", nii, "--force"], check=True)
    zyx = np.ascontiguousarray(np.asarray(slabscope.load(nii)).T)
    stored = zarr.open_array(path, mode="w", shape=zyx.shape, chunks=(chunk,) * 3, dtype=zyx.dtype)
    stored[:] = zyx
    os.remove(nii)
    return path


def single(path: str, params: dict) -> tuple:
    import zarr

    import slabscope

    wall, used = time.perf_counter(), cpu()
    zyx = zarr.open_array(path, mode="r")[:]
    read = time.perf_counter() - wall
    result = slabscope.analyze(slabscope.Volume.from_array(zyx.T), **params)
    return result, {"wall_s": time.perf_counter() - wall, "cpu_s": cpu() - used, "read_s": read}


def cluster(client, path: str, params: dict) -> tuple:
    from distributed import get_task_stream

    import slabscope.dask

    before = sum(client.run(cpu).values())
    wall, used = time.perf_counter(), cpu()
    with get_task_stream(client) as stream:
        result = slabscope.dask.analyze_array(client, path, axes="zyx", **params)
    elapsed = time.perf_counter() - wall
    workers = sum(client.run(cpu).values()) - before
    tasks = defaultdict(list)
    for t in stream.data:
        for s in t["startstops"]:
            if s["action"] == "compute":
                tasks[t["key"][0] if isinstance(t["key"], tuple) else t["key"]].append(s["stop"] - s["start"])
    by_kind = defaultdict(list)
    for key, times in tasks.items():
        kind = key.split("-")[0]
        by_kind[kind].extend(times)
    figures = {k: {"tasks": len(v), "sum_s": round(sum(v), 3), "max_s": round(max(v), 3)} for k, v in by_kind.items()}
    mine = cpu() - used
    return result, {"wall_s": elapsed, "cpu_s": workers + mine, "client_cpu_s": mine, "tasks": figures}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--chunk", type=int, default=64)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--params", action="append", choices=sorted(PARAMS))
    parser.add_argument("--folder", default=tempfile.gettempdir())
    args = parser.parse_args()
    from distributed import Client, LocalCluster

    path = store(args.folder, args.size, args.chunk)
    with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, memory_limit="6GiB", dashboard_address=None) as lc, Client(lc) as client:
        for name in args.params or ["paper", "defaults"]:
            params = PARAMS[name]
            one, alone = single(path, params)
            got, split = cluster(client, path, params)
            print(
                json.dumps(
                    {
                        "params": name,
                        "size": args.size,
                        "chunk": args.chunk,
                        "workers": args.workers,
                        "equal": got.to_dict() == one.to_dict(),
                        "single": alone,
                        "cluster": split,
                        "wall_ratio": split["wall_s"] / alone["wall_s"],
                        "cpu_ratio": split["cpu_s"] / alone["cpu_s"],
                    }
                ),
                flush=True,
            )


if __name__ == "__main__":
    main()
