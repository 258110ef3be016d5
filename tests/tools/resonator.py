"""The gas-column/slab resonator strip (cases/fsi_resonator.ini) at a given resolution: the
overrides that set grid.dx and keep the strip 3 cells high, with the slab's face layer and the
face probe one particle layer wide (test_fsi_resonator.py, test_gridp_beside.py)."""
C_G = 1.4 ** 0.5  # the gas's sound speed, sqrt(gamma p0 / rho0)


def strip_args(cells):
    """mpmfsi overrides for the strip at `cells` cells per metre."""
    dx = 1.0 / cells
    h = 3 * dx
    return [f"grid.dx={dx!r}", f"domain.hi=1.4 {h!r}", f"geometry.gas.hi=1.0 {h!r}",
            f"geometry.slab.hi=1.4 {h!r}", f"geometry.face.hi={1 + dx / 2!r} {h!r}",
            f"probe.face.point={1 + dx / 4!r} {dx / 4!r}"]
