"""Where time.method = ssprk2 is refused: one error line naming case.ini, its line and the key,
exit 2, no output folder (the rules of the ERK pairs' other pairings).
  - coupling.time = multirate (MRIStep steps the gas with its own coupling table) and
    staggered (the classic update only): named at time.method;
  - fluid.strain_rate = lagged: each stage must read the rate of its own state;
and accepted with coupling.time = monolithic (the coupled fsi_pulse runs to a short end).
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_ssprk2_input")
fsi = open(mt.case("fsi_pulse.ini")).read()
sod = open(mt.case("sod.ini")).read()


def with_time(text, lines):
    """text with `lines` after its [time] header: (new text, number of the method line)."""
    head, tail = text.split("[time]\n", 1)
    out = head + "[time]\n" + "".join(l + "\n" for l in lines) + tail
    return out, mt.line_starting(out, "method = ssprk2")


for scheme in ("multirate", "staggered"):
    text, line = with_time(fsi.replace("[coupling]\n", f"[coupling]\ntime = {scheme}\n", 1)
                           .replace("method = usl\n", ""), ["method = ssprk2"])
    mt.expect_input_error(check, f"ssprk2 with coupling.time = {scheme}", text, "time.method",
                          line, "coupling.time")
assert "method = usl\n" in sod, "cases/sod.ini no longer sets time.method = usl"
text, line = with_time(sod.replace("method = usl\n", ""), ["method = ssprk2"])
text = text.replace("[fluid]\n", "[fluid]\nstrain_rate = lagged\n", 1)
mt.expect_input_error(check, "ssprk2 with fluid.strain_rate = lagged", text, "fluid.strain_rate",
                      mt.line_starting(text, "strain_rate = lagged"), "ssprk2")
out = mt.outdir("ssprk2_monolithic")
p = mt.run(["run", mt.case("fsi_pulse.ini"), f"output.dir={out}", "time.method=ssprk2",
            "time.t_end=0.02", "output.interval=0.02", "run.progress=false"], check=False)
check(p.returncode == 0, f"ssprk2 with coupling.time = monolithic (fsi_pulse to t = 0.02): exit "
      f"{p.returncode}")
sys.exit(check.finish())
