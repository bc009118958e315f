#!/usr/bin/env python3
"""Converts a model to .spt on a Dask cluster: spt's out-of-core build, one task per job.

    python3 tools/cluster/convert.py INPUT OUTPUT --scheduler-file sched.json
    python3 tools/cluster/convert.py INPUT OUTPUT --scheduler tcp://host:8786 --dir /shared/jobs

The driver runs `spt jobs plan` here, submits `spt jobs build DIR J` for every job to the
cluster (Dask retries a task whose worker dies, and a failed one up to --retries times),
prints each job as it ends, then runs `spt jobs join` here. When the join asks for the
parts again (exit 3: a larger error scale, a mesh's orientation), it submits them again.
Run again after a failure, it keeps the plan and every part already built.

Every worker must see the job directory (DIR, default OUTPUT.jobs) and the spt binary
(--spt) at the same paths. Install: `pip install "dask[distributed]"` (docs/cluster.md).
With the same --memory, the file is byte for byte `spt convert --out-of-core`'s.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

REBUILD = 3


def run_timed(args):
    """Runs `args`; returns (status, seconds, peak resident KiB, stdout, stderr)."""
    start = time.time()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        proc = subprocess.Popen(args, stdout=out, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        return (proc.returncode, time.time() - start, usage.ru_maxrss,
                out.read().decode(errors="replace"), err.read().decode(errors="replace"))


def build_job(spt, jobs_dir, job):
    """A task: builds one job on a worker; raises on failure so that Dask retries it."""
    from dask.distributed import get_worker
    status, seconds, peak, out, err = run_timed([spt, "jobs", "build", jobs_dir, str(job)])
    if status != 0:
        raise RuntimeError(f"job {job}: spt jobs build exited {status}: {err.strip()}")
    return {
        "job": job,
        "seconds": seconds,
        "peak_kib": peak,
        "worker": get_worker().address,
        "kept": "kept (already built)" in out,
    }


def worker_peak_kib():
    """The worker process's own peak resident memory (spt runs as its child)."""
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def build_all(client, spt, jobs_dir, jobs, retries, round_):
    """Submits every job, prints each as it ends; returns their results."""
    from dask.distributed import as_completed
    futures = [
        client.submit(build_job, spt, jobs_dir, j, retries=retries, pure=False,
                      key=f"spt-build-{round_}-{j}")
        for j in range(jobs)
    ]
    results = []
    for done, future in enumerate(as_completed(futures), 1):
        r = future.result()
        results.append(r)
        how = "kept" if r["kept"] else "built"
        print(f"[{done:>4}/{jobs}] job {r['job']} {how} on {r['worker']} in "
              f"{r['seconds']:.1f} s, peak {r['peak_kib'] / 2**20:.2f} GiB", flush=True)
    return results


def per_worker(results, client):
    """Per worker: jobs, busy seconds, largest job peak, the worker process's peak."""
    own = client.run(worker_peak_kib)
    table = {}
    for r in results:
        w = table.setdefault(r["worker"], {"jobs": 0, "seconds": 0.0, "job_peak_kib": 0})
        w["jobs"] += 1
        w["seconds"] += r["seconds"]
        w["job_peak_kib"] = max(w["job_peak_kib"], r["peak_kib"])
    for address, w in table.items():
        w["process_peak_kib"] = own.get(address)
    return table


def convert(args, client):
    """Plan, build on the cluster, join; returns the report."""
    jobs_dir = os.path.abspath(args.dir or args.output + ".jobs")
    spt = os.path.abspath(args.spt)
    start = time.time()
    plan = [spt, "jobs", "plan", args.input, jobs_dir]
    if args.memory:
        plan += ["--memory", str(args.memory)]
    status, plan_s, plan_peak, out, err = run_timed(plan)
    if status != 0:
        sys.exit(f"spt jobs plan failed: {err.strip()}")
    print(out.strip().splitlines()[-1], flush=True)
    with open(os.path.join(jobs_dir, "manifest.json")) as f:
        jobs = len(json.load(f)["jobs"])
    results, build_s = [], 0.0
    for round_ in range(4):
        t = time.time()
        results += build_all(client, spt, jobs_dir, jobs, args.retries, round_)
        build_s += time.time() - t
        join = [spt, "jobs", "join", jobs_dir, args.output] + (["--clean"] if args.clean else [])
        status, join_s, join_peak, out, err = run_timed(join)
        if status != REBUILD:
            break
        print(f"the join asks for the parts again: {err.strip()}", flush=True)
    if status != 0:
        sys.exit(f"spt jobs join failed: {err.strip()}")
    print(out.strip(), flush=True)
    return {
        "jobs": jobs,
        "wall_s": time.time() - start,
        "plan_s": plan_s,
        "plan_peak_kib": plan_peak,
        "build_s": build_s,
        "join_s": join_s,
        "join_peak_kib": join_peak,
        "workers": per_worker(results, client),
        "results": results,
    }


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("input", help="the model: a PLY, LAS or LAZ file")
    p.add_argument("output", help="the .spt file to write")
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--scheduler", help="the Dask scheduler's address (tcp://host:8786)")
    where.add_argument("--scheduler-file", help="the file `dask scheduler` wrote")
    p.add_argument("--dir", help="the job directory every worker sees (default OUTPUT.jobs)")
    p.add_argument("--spt", default=shutil.which("spt") or "target/release/spt",
                   help="the spt binary, at a path every worker sees")
    p.add_argument("--memory", type=int, help="memory budget of one job in MiB (spt's --memory)")
    p.add_argument("--retries", type=int, default=2, help="retries of a failed job (default 2)")
    p.add_argument("--clean", action="store_true", help="remove the job directory once written")
    p.add_argument("--report", help="write the timings and memory as JSON here")
    args = p.parse_args()
    from dask.distributed import Client
    client = (Client(args.scheduler) if args.scheduler
              else Client(scheduler_file=args.scheduler_file))
    report = convert(args, client)
    print(f"{report['jobs']} jobs in {report['wall_s']:.1f} s: plan {report['plan_s']:.1f} s, "
          f"build {report['build_s']:.1f} s, join {report['join_s']:.1f} s")
    for address, w in sorted(report["workers"].items()):
        own = w["process_peak_kib"]
        own = f", worker process {own / 2**20:.2f} GiB" if own else " (worker gone)"
        print(f"  {address}: {w['jobs']} jobs, {w['seconds']:.1f} s, "
              f"peak {w['job_peak_kib'] / 2**20:.2f} GiB per job{own}")
    if args.report:
        with open(args.report, "w") as f:
            json.dump(report, f, indent=1)


if __name__ == "__main__":
    main()
