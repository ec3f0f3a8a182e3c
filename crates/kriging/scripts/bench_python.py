#!/usr/bin/env python3
"""Times PyKrige 1.7.3 and GSTools 1.7.0 on the problem of benches/kriging_geo.rs.

n = 2000 scattered points (Halton sequence, bases 2 and 3, on [0, 10000]^2), values
sin(x / 1500) + cos(y / 900) + 1e-4 x, ordinary kriging with a given spherical variogram
(nugget 0.05, partial sill 1.0, range 3000), predictions and kriging variances on a 100 x 100 grid
over [0, 10000]^2. One run = build the model ("fit") + predict the grid; the best of `--repeat`
runs is reported, as criterion reports a typical time for ours.

Run (nothing is installed into the repository):

    python3 -m venv /tmp/kvenv
    /tmp/kvenv/bin/pip install pykrige==1.7.3 gstools==1.7.0
    /tmp/kvenv/bin/python crates/kriging/scripts/bench_python.py

NumPy's BLAS may use every core (both libraries lean on it); the thread count is printed.
"""

import argparse
import time

import numpy as np

N = 2000
GRID = 100
NUGGET, SILL, RANGE = 0.05, 1.0, 3000.0


def radical_inverse(i, b):
    f, r = 1.0, 0.0
    while i > 0:
        f /= b
        r += f * (i % b)
        i //= b
    return r


def data():
    x = np.array([10000.0 * radical_inverse(i, 2) for i in range(1, N + 1)])
    y = np.array([10000.0 * radical_inverse(i, 3) for i in range(1, N + 1)])
    z = np.sin(x / 1500.0) + np.cos(y / 900.0) + 1e-4 * x
    return x, y, z


def grid():
    g = np.linspace(0.0, 10000.0, GRID)
    return g, g


def run_pykrige(x, y, z, gx, gy):
    from pykrige.ok import OrdinaryKriging

    k = OrdinaryKriging(x, y, z, variogram_model="spherical",
                        variogram_parameters={"psill": SILL, "range": RANGE, "nugget": NUGGET})
    zz, ss = k.execute("grid", gx, gy, backend="vectorized")
    return np.asarray(zz), np.asarray(ss)


def run_gstools(x, y, z, gx, gy):
    import gstools as gs

    m = gs.Spherical(dim=2, var=SILL, len_scale=RANGE, nugget=NUGGET)
    k = gs.krige.Ordinary(m, (x, y), z, exact=True)
    f, v = k((gx, gy), mesh_type="structured")
    return np.asarray(f).T, np.asarray(v).T  # GSTools: [x, y]; PyKrige: [y, x]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--only", choices=["pykrige", "gstools"], default=None)
    args = ap.parse_args()
    try:
        from threadpoolctl import threadpool_info

        threads = {i["internal_api"]: i["num_threads"] for i in threadpool_info()}
    except Exception:  # noqa: BLE001
        threads = "unknown"
    import gstools
    import pykrige

    print(f"PyKrige {pykrige.__version__}, GSTools {gstools.__version__}, NumPy {np.__version__}, "
          f"BLAS threads {threads}")
    x, y, z = data()
    gx, gy = grid()
    results = {}
    for name, fn in [("pykrige", run_pykrige), ("gstools", run_gstools)]:
        if args.only and name != args.only:
            continue
        best = float("inf")
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            out = fn(x, y, z, gx, gy)
            best = min(best, time.perf_counter() - t0)
        results[name] = out
        print(f"{name:8s} fit + {GRID}x{GRID} grid (values and variances), n = {N}: "
              f"best of {args.repeat}: {best:.3f} s; grid mean {out[0].mean():.12f}, "
              f"variance mean {out[1].mean():.12f}", flush=True)
    if len(results) < 2:
        return
    dz = np.max(np.abs(results["pykrige"][0] - results["gstools"][0]))
    dv = np.max(np.abs(results["pykrige"][1] - results["gstools"][1]))
    print(f"PyKrige vs GSTools: predictions differ by {dz:.1e}, variances by {dv:.1e}")


if __name__ == "__main__":
    main()
