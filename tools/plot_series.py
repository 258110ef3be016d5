#!/usr/bin/python3
"""Plot columns of one or more diagnostics.csv files against time.

Usage: /usr/bin/python3 tools/plot_series.py OUT.png COLUMN[,COLUMN...] LABEL=DIR [LABEL=DIR ...]
e.g.   tools/plot_series.py energy.png total,kinetic usl=out/a bs32=out/b
Each DIR is an mpmfsi output folder; one line per (run, column)."""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main(argv):
    if len(argv) < 4:
        sys.exit(__doc__)
    out, columns, runs = argv[1], argv[2].split(","), argv[3:]
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for run in runs:
        label, folder = run.split("=", 1)
        d = np.genfromtxt(os.path.join(folder, "diagnostics.csv"), delimiter=",", names=True)
        for c in columns:
            ax.plot(d["t"], d[c], label=f"{label}: {c}" if len(columns) > 1 else label)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(", ".join(columns) + " [J]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print("wrote", out)


if __name__ == "__main__":
    main(sys.argv)
