#!/usr/bin/env python3
"""Checks the Dask driver (tools/cluster/convert.py) on a local cluster: a scheduler and two
worker processes started here. Prints a Markdown report; exits 1 if a check fails.

    python3 tools/cluster/check.py --points 3000000 --memory 256        # CI
    python3 tools/cluster/check.py --input city_200m.las --memory 8192 --no-faults  # 200 M

1. `spt convert --out-of-core` of the input, then the driver on the cluster: the two
   files must be byte-identical (compared by SHA-256), with wall time
   and peak memory per worker.
2. A worker killed (SIGKILL, by its process id, with its spt child) in the middle of a job:
   Dask gives the job to another worker and the file is the same.
3. A part file truncated after a run: `spt jobs join` refuses it, naming the file; the
   driver run again builds that job only, and the file is the same.
4. A job input damaged on disk: `spt jobs build` refuses it by its checksum.
5. A degenerate cloud whose error scale only the join can decide: the join exits 3, the
   driver builds the parts again, and the file is `spt convert --out-of-core`'s.
"""

import argparse
import hashlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
from convert import run_timed  # noqa: E402

failures = []


def check(ok, what):
    print(f"- {'ok' if ok else 'FAILED'}: {what}", flush=True)
    if not ok:
        failures.append(what)


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 22), b""):
            h.update(block)
    return h.hexdigest()


class Cluster:
    """`dask scheduler` and two `dask worker` processes (one thread each, no memory limit:
    the jobs run as child processes)."""

    def __init__(self, work):
        self.file = os.path.join(work, "scheduler.json")
        quiet = dict(stdout=subprocess.DEVNULL, stderr=open(os.path.join(work, "dask.log"), "w"))
        self.procs = [subprocess.Popen(
            ["dask", "scheduler", "--scheduler-file", self.file, "--port", "0",
             "--no-dashboard"], **quiet)]
        while not os.path.exists(self.file):
            time.sleep(0.2)
        for k in range(2):
            self.procs.append(subprocess.Popen(
                ["dask", "worker", "--scheduler-file", self.file, "--nthreads", "1",
                 "--memory-limit", "0", "--no-dashboard", "--name", f"w{k}"], **quiet))
        from dask.distributed import Client
        self.client = Client(scheduler_file=self.file)
        self.client.wait_for_workers(2, timeout=120)

    def worker_pids(self):
        return self.client.run(os.getpid)

    def close(self):
        self.client.close()
        for p in reversed(self.procs):
            p.send_signal(signal.SIGINT)
        for p in self.procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()


def driver(args, output, jobs_dir, report, background=False):
    cmd = [sys.executable, os.path.join(HERE, "convert.py"), args.input, output,
           "--scheduler-file", args.cluster.file, "--dir", jobs_dir, "--spt", args.spt,
           "--memory", str(args.memory), "--report", report]
    if background:
        return subprocess.Popen(cmd)
    status = subprocess.call(cmd)
    with open(report) as f:
        return status, json.load(f) if status == 0 else None


def kill_mid_job(cluster, run):
    """Waits until a worker has run an spt job for half a second, then kills the worker
    and the job (a machine lost); returns (worker address, job number), or None when
    the driver `run` ended first."""
    import psutil
    pids = cluster.worker_pids()
    while run.poll() is None:
        for address, pid in pids.items():
            try:
                children = psutil.Process(pid).children(recursive=True)
            except psutil.NoSuchProcess:
                continue
            for c in children:
                cmd = c.cmdline()
                if "build" in cmd and time.time() - c.create_time() > 0.5:
                    os.kill(pid, signal.SIGKILL)
                    c.kill()
                    return address, int(cmd[-1])
        time.sleep(0.05)
    return None


def reference(args, work):
    out = os.path.join(work, "reference.spt")
    status, seconds, peak, _, err = run_timed(
        [args.spt, "convert", args.input, out, "--out-of-core", "--memory", str(args.memory)])
    if status != 0:
        sys.exit(f"spt convert failed: {err}")
    digest = sha256(out)
    os.remove(out)  # the cluster's file is compared by its digest: half the disk
    return digest, seconds, peak


def worker_rows(report):
    for address, w in sorted(report["workers"].items()):
        own = w["process_peak_kib"]
        own = f"{own / 2**20:.2f}" if own else "gone"
        yield (f"| {address} | {w['jobs']} | {w['seconds']:.1f} | "
               f"{w['job_peak_kib'] / 2**20:.2f} | {own} |")


def sizes(jobs_dir, out, jobs):
    """The bytes each step reads and writes: job inputs, parts, the file."""
    with open(os.path.join(jobs_dir, "manifest.json")) as f:
        m = json.load(f)
    inputs = [sum(f["bytes"] for f in j["files"]) for j in m["jobs"]]
    parts = [os.path.getsize(os.path.join(jobs_dir, f"job{j}.part")) for j in range(jobs)]
    points = [j["points"] for j in m["jobs"]]
    gb = lambda b: f"{b / 1e9:.2f} GB"
    return (f"bytes: job inputs {gb(sum(inputs))} ({sum(inputs) / sum(points):.1f} per point; "
            f"largest job {gb(max(inputs))}), parts {gb(sum(parts))} ({sum(parts) / sum(points):.1f} "
            f"per point; largest {gb(max(parts))}), file {gb(os.path.getsize(out))}; "
            f"points per job {min(points):,} to {max(points):,}\n")


def clean_run(args, work, digest):
    out, jobs_dir = os.path.join(work, "cluster.spt"), os.path.join(work, "jobs")
    status, report = driver(args, out, jobs_dir, os.path.join(work, "clean.json"))
    check(status == 0 and sha256(out) == digest,
          "the cluster's file is byte-identical to spt convert --out-of-core's")
    print(f"\ncluster: {report['jobs']} jobs, wall {report['wall_s']:.1f} s (plan "
          f"{report['plan_s']:.1f} s, build {report['build_s']:.1f} s, join "
          f"{report['join_s']:.1f} s); plan peak {report['plan_peak_kib'] / 2**20:.2f} GiB, "
          f"join peak {report['join_peak_kib'] / 2**20:.2f} GiB\n")
    print("| worker | jobs | busy s | peak of a job, GiB | worker process peak, GiB |")
    print("| --- | --- | --- | --- | --- |")
    print("\n".join(worker_rows(report)) + "\n")
    print(sizes(jobs_dir, out, report["jobs"]))
    os.remove(out)
    if args.no_faults:
        shutil_rmtree(jobs_dir)
    return report


def killed_worker(args, work, digest):
    out, jobs_dir = os.path.join(work, "killed.spt"), os.path.join(work, "jobs-killed")
    run = driver(args, out, jobs_dir, os.path.join(work, "killed.json"), background=True)
    killed = kill_mid_job(args.cluster, run)
    if killed is None:
        check(False, "a worker killed in the middle of a job: the run ended first")
        return
    address, job = killed
    print(f"killed worker {address} and its spt in the middle of job {job}")
    status = run.wait()
    with open(os.path.join(work, "killed.json")) as f:
        report = json.load(f)
    again = [r["worker"] for r in report["results"] if r["job"] == job]
    check(status == 0 and again and again[0] != address and sha256(out) == digest,
          f"job {job} was built again on {again[0] if again else 'no worker'}, the file the same")
    os.remove(out)
    shutil_rmtree(jobs_dir)


def truncated_part(args, work, digest):
    out, jobs_dir = os.path.join(work, "cut.spt"), os.path.join(work, "jobs")
    part = os.path.join(jobs_dir, "job1.part")
    os.truncate(part, os.path.getsize(part) // 2)
    status, _, _, _, err = run_timed([args.spt, "jobs", "join", jobs_dir, out])
    check(status == 1 and "job1.part" in err and "truncated" in err,
          f"the join refuses the truncated part: {err.strip()}")
    status, report = driver(args, out, jobs_dir, os.path.join(work, "cut.json"))
    built = sorted(r["job"] for r in report["results"] if not r["kept"])
    check(status == 0 and built == [1] and sha256(out) == digest,
          f"the rerun built job 1 only ({built}), the file the same")
    os.remove(out)


def damaged_input(args, work):
    jobs_dir = os.path.join(work, "jobs")
    with open(os.path.join(jobs_dir, "manifest.json")) as f:
        own = json.load(f)["jobs"][2]["files"][0]["name"]
    os.remove(os.path.join(jobs_dir, "job2.part.json"))
    with open(os.path.join(jobs_dir, own), "r+b") as f:
        f.seek(1000)
        byte = f.read(1)
        f.seek(1000)
        f.write(bytes([byte[0] ^ 0x40]))
    status, _, _, _, err = run_timed([args.spt, "jobs", "build", jobs_dir, "2"])
    check(status == 1 and own in err and "damaged" in err,
          f"a damaged job input is refused: {err.strip()}")


def rebuilt_parts(args, work):
    """A degenerate cloud whose leaves' error scale only the join can know: the join
    exits 3, the driver builds the parts again, and the file is one process's."""
    tiny = os.path.join(work, "tiny.ply")
    rows = ["0 0 0", "0 0 0", "5.831554006032442e-39 -6.310887241768095e-30 5.6492941212700346e-39",
            "7.681846387076256e31 1.6884937804572382e25 4.3053280908255565e21"]
    with open(tiny, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\n"
                "property double y\nproperty double z\nend_header\n" + "\n".join(rows) + "\n")
    one, out = os.path.join(work, "tiny_one.spt"), os.path.join(work, "tiny.spt")
    subprocess.check_call([args.spt, "convert", tiny, one, "--out-of-core"],
                          stdout=subprocess.DEVNULL)
    cmd = [sys.executable, os.path.join(HERE, "convert.py"), tiny, out, "--scheduler-file",
           args.cluster.file, "--spt", args.spt, "--clean"]
    run = subprocess.run(cmd, capture_output=True, text=True)
    asked = "asks for the parts again" in run.stdout
    check(run.returncode == 0 and asked and sha256(out) == sha256(one),
          "a join that needs another error scale: the driver built the parts again, "
          "the file is one process's")


def shutil_rmtree(path):
    import shutil
    shutil.rmtree(path, ignore_errors=True)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--input", help="the model (default: a generated cloud of --points)")
    p.add_argument("--points", type=int, default=3_000_000)
    p.add_argument("--memory", type=int, default=256, help="MiB per job (spt's --memory)")
    p.add_argument("--spt", default=os.path.join(ROOT, "target/release/spt"))
    p.add_argument("--work", help="working directory (default: a temporary one)")
    p.add_argument("--no-faults", action="store_true",
                   help="the clean run only (checks 2 to 4 convert the input twice more)")
    args = p.parse_args()
    args.spt = os.path.abspath(args.spt)
    work = args.work or tempfile.mkdtemp(prefix="spt-cluster-")
    os.makedirs(work, exist_ok=True)
    if not args.input:
        args.input = os.path.join(work, f"cloud_{args.points}.las")
        subprocess.check_call([os.path.join(ROOT, "target/release/examples/gen_cloud"),
                               "--points", str(args.points), "--out", args.input])
    print(f"# spt on a local Dask cluster: {os.path.basename(args.input)}, --memory "
          f"{args.memory}, {os.cpu_count()} cores, {time.strftime('%Y-%m-%d')}\n")
    digest, seconds, peak = reference(args, work)
    print(f"spt convert --out-of-core: {seconds:.1f} s, peak {peak / 2**20:.2f} GiB\n")
    args.cluster = Cluster(work)
    try:
        clean_run(args, work, digest)
        if not args.no_faults:
            killed_worker(args, work, digest)
            truncated_part(args, work, digest)
            damaged_input(args, work)
            rebuilt_parts(args, work)
    finally:
        args.cluster.close()
    if not args.work:
        shutil_rmtree(work)
    if failures:
        sys.exit(f"{len(failures)} checks failed")


if __name__ == "__main__":
    main()
