"""fluid.pic_fraction: the gas's own PIC share, in place of transfer.pic_fraction, for the gas only.

Case: cases/fsi_box.ini (gas with a pressure pulse around an elastic block) with
coupling.scheme = none, so that the two phases do not act on each other and each module's
particles depend on its own transfer only, and the block set shearing (v_x = 0.1 sin(2 pi y)),
so that a PIC share changes it; to t = 0.12 in fixed steps of 1e-3 (usl, time.dt_max below
both modules' stable steps: the gas's stable step depends on its velocities, and would otherwise
change the solid's steps too).
- fluid.pic_fraction = 0.3 leaves the solid bitwise as with no PIC share at all, and changes
  the gas;
- its gas is bitwise the gas of transfer.pic_fraction = 0.3 (the same update, read from the
  gas's own key), whose solid differs (the global key damps both).
- fluid.pic_fraction with an ERK pair (bs32) is refused: exit 2, one error naming the key.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_gas_pic")
BASE = ["coupling.scheme=none", "time.method=usl", "time.t_end=0.12", "time.dt_max=1e-3",
        "solid.block.velocity_field=0.1*sin(2*pi*y); 0",
        "output.interval=1e9", "run.progress=false"]


def final(label, extra):
    out = mt.outdir("gas_pic_" + label)
    mt.run(["run", mt.case("fsi_box.ini"), f"output.dir={out}"] + BASE + extra)
    path = mt.snapshots(out)[-1][1]
    return mt.particles(path, "solid"), mt.particles(path, "fluid")


def same(a, b, fields=("x", "v")):
    return all(np.array_equal(a[f], b[f]) for f in fields) and np.array_equal(a["id"], b["id"])


solid0, gas0 = final("flip", [])
solid_g, gas_g = final("gas", ["fluid.pic_fraction=0.3"])
solid_t, gas_t = final("all", ["transfer.pic_fraction=0.3"])
check(solid_g["time"] == solid0["time"] > 0,
      f"all three end at the same time ({solid0['time']:.4g})")
check(same(solid_g, solid0), "fluid.pic_fraction = 0.3: the solid is bitwise the pure-FLIP solid")
dv = float(np.abs(gas_g["v"] - gas0["v"]).max())
check(dv > 0, f"fluid.pic_fraction = 0.3: the gas's velocities change (largest change {dv:.3g})")
check(same(gas_g, gas_t), "the gas under fluid.pic_fraction = 0.3 is bitwise the gas under "
      "transfer.pic_fraction = 0.3")
ds = float(np.abs(solid_t["v"] - solid0["v"]).max())
check(ds > 0, f"transfer.pic_fraction = 0.3 changes the solid too (largest change {ds:.3g})")
p = mt.run(["check", mt.case("fsi_box.ini"), "fluid.pic_fraction=0.3", "time.method=bs32"],
           check=False)
errs = [l for l in p.stderr.splitlines() if l.startswith("error:")]
check(p.returncode == 2 and len(errs) == 1 and "fluid.pic_fraction" in errs[0],
      f"with bs32: exit {p.returncode}, {errs[0] if errs else 'no error line'}")
sys.exit(check.finish())
