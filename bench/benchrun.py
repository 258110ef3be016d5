"""What the bench drivers share: run mpmfsi (under mpiexec for more than one rank) in a
scratch output folder and read back its summary.json and timers.csv; the log-log interpolation
of a cost at equal error."""
import csv
import json
import math
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_btl_vader_single_copy_mechanism="none", OMPI_MCA_mpi_yield_when_idle="1")


def git(*args):
    """`git args` in the repository, its output stripped; "unknown" where git cannot tell."""
    try:
        return subprocess.run(["git", "-C", ROOT] + list(args), capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def run_case(binary, case, overrides, ranks):
    """Run `binary run case output.dir=... overrides` on ranks; returns (summary, timers) with
    timers the mean seconds per phase."""
    with tempfile.TemporaryDirectory() as out:
        args = [binary, "run", case, f"output.dir={out}"] + list(overrides)
        if ranks > 1:
            args = ["mpiexec", "-n", str(ranks)] + args
        subprocess.run(args, check=True, env=ENV, capture_output=True)
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
        with open(os.path.join(out, "timers.csv")) as f:
            timers = {r["phase"]: float(r["mean_s"]) for r in csv.DictReader(f)}
    return summary, timers


def loglog(x, p0, p1):
    """y at x on the straight line through the points p0 = (x0, y0), p1 = (x1, y1) in log-log
    (a wall time at a given error between two runs; x0 != x1, all positive)."""
    (x0, y0), (x1, y1) = p0, p1
    return math.exp(math.log(y0) + math.log(x / x0) / math.log(x1 / x0) * math.log(y1 / y0))
