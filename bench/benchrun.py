"""What the throughput drivers share: run mpmfsi (under mpiexec for more than one rank) in a
scratch output folder and read back its summary.json and timers.csv."""
import csv
import json
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_btl_vader_single_copy_mechanism="none", OMPI_MCA_mpi_yield_when_idle="1")


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
