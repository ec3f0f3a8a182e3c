#!/usr/bin/env python3
"""Times GSTools 1.7.0's conditioned random field on the job of benches/kriging_sgs.rs.

The job (the same as the Rust bench and `examples/sgs_timing.rs`): 100 realisations of a
200 x 200 grid over [0, 10000]^2 conditioned on 2,000 points (Halton sequence, bases 2 and 3, on
[0, 10000]^2) with values sin(x / 1500) + cos(y / 900) + 1e-4 x; exponential variogram without
nugget, partial sill 1 and practical range 3000 (GSTools: Exponential(var=1, len_scale=1000), its
length scale being a third of the practical range), simple kriging with the data mean.

GSTools does not simulate sequentially: gstools.CondSRF (1.7.0) kriges the data onto the grid once
(a global system over all 2,000 points, reused by later realisations), draws an unconditional
field per realisation (randomisation method, 1000 modes) and adds it scaled by the kriging
standard deviation over the sill's (`krige + sqrt(krige_var / var) * unconditional`). The data are
honoured and the pointwise variance is the kriging variance, but it is a different method (and
approximation) from sequential Gaussian simulation: compare the times, not the fields.

Run (nothing is installed into the repository):

    pip install gstools==1.7.0        # or in a venv
    python3 crates/kriging/scripts/sgs_gstools_timing.py [realisations]

Prints the total time, the first realisation's (kriging included) and the mean of the others,
and the ensemble's mean of the pointwise means and variances (for a sanity check against the
Rust example's output). NumPy's BLAS and GSTools' OpenMP may use every core.
"""

import os
import sys
import time

import gstools as gs
import numpy as np

N = 2000
GRID = 200
SILL, RANGE = 1.0, 3000.0


def radical_inverse(i, b):
    f, r = 1.0, 0.0
    while i > 0:
        f /= b
        r += f * (i % b)
        i //= b
    return r


def main():
    realisations = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    x = np.array([10000.0 * radical_inverse(i, 2) for i in range(1, N + 1)])
    y = np.array([10000.0 * radical_inverse(i, 3) for i in range(1, N + 1)])
    z = np.sin(x / 1500.0) + np.cos(y / 900.0) + 1e-4 * x
    g = 10000.0 * np.arange(GRID) / (GRID - 1)
    model = gs.Exponential(dim=2, var=SILL, len_scale=RANGE / 3.0, nugget=0.0)
    t0 = time.perf_counter()
    krige = gs.krige.Simple(model, (x, y), z, mean=float(z.mean()), exact=True, pseudo_inv=False)
    cond = gs.CondSRF(krige)
    cond.set_pos([g, g], "structured")
    fields = np.empty((realisations, GRID, GRID))
    times = []
    for r in range(realisations):
        t = time.perf_counter()
        fields[r] = cond(seed=2024 + r)
        times.append(time.perf_counter() - t)
    total = time.perf_counter() - t0
    print(f"gstools {gs.__version__}, numpy {np.__version__}, {os.cpu_count()} CPUs")
    print(
        f"{realisations} realisations of a {GRID} x {GRID} grid conditioned on {N} points: "
        f"{total:.2f} s (first realisation {times[0]:.2f} s, then {np.mean(times[1:]):.3f} s each)"
    )
    print(
        f"ensemble: mean of the means {fields.mean(axis=0).mean():.4f}, mean of the variances "
        f"{fields.var(axis=0, ddof=1).mean():.4f} (data mean {z.mean():.4f})"
    )


if __name__ == "__main__":
    main()
