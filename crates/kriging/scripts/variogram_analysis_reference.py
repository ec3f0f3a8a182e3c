#!/usr/bin/env python3
"""Reference numbers for crates/kriging/tests/meuse_variogram.rs and tests/variogram_fit.rs (issue 37,
item 4) from GSTools 1.7.0.

Writes tests/data/meuse_variogram_reference.json (Meuse: GPL-3 test fixture like meuse.csv, not
shipped) and tests/data/nested_fit_reference.json (generated numbers, sections 3 and 4).
Run (nothing is installed into the repository):

    pip install gstools==1.7.0 scipy      # or in a venv
    python3 crates/kriging/scripts/variogram_analysis_reference.py

Data: Meuse, log zinc (tests/data/meuse.csv). Binning: 15 equal intervals up to 1500.5 m (the
crate's Binning { bins: 15, max_lag: MaxLag::Distance(1500.5) }); the script checks that no pair
distance lies within 1e-6 of an interval edge, so that half-open GSTools bins and the crate's agree.

1. Empirical variograms, `gs.vario_estimate(..., bin_edges, estimator=..., direction=..., angles_tol=...,
   bandwidth=...)`: omnidirectional and directional (0, 45, 90, 135 degrees counter-clockwise from x,
   tolerance 22.5 degrees; 0 and 90 also with bandwidth 250.5 m), Matheron and Cressie. Dowd (not
   in GSTools): numpy, 1.099 median(|dz|)^2 over the same pairs (pair selection as GSTools').
2. Fits to the omnidirectional Matheron variogram with pair-count weights (GSTools minimises
   sum (w r)^2 with weights = sqrt(counts), i.e. sum counts r^2, the crate's FitWeights::PairCounts):
   - Matern with nu free (GSTools bounds nu in [0.2, 30]) and a nugget. GSTools' Matern uses
     sqrt(nu) h / len_scale, so the crate's scale a = len_scale / sqrt(nu).
   - Spherical + Exponential (GSTools SumModel) with a nugget. Crate: exponential practical range
     = 3 len_scale; spherical range = len_scale.
"""
import json
import os

import gstools as gs
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "tests", "data")

raw = np.loadtxt(os.path.join(DATA, "meuse.csv"), delimiter=",", skiprows=1)
x, y, z = raw[:, 0], raw[:, 1], np.log(raw[:, 2])
BINS, HMAX = 15, 1500.5
dh = HMAX / BINS
edges = dh * np.arange(BINS + 1)

# No pair distance on an edge.
dx = x[None, :] - x[:, None]
dy = y[None, :] - y[:, None]
iu = np.triu_indices(len(x), 1)
dist = np.hypot(dx, dy)[iu]
assert np.min(np.abs(dist[:, None] - edges[None, :])) > 1e-6

out = {"gstools": gs.__version__, "bins": BINS, "max_lag": HMAX, "cases": []}
CASES = [(None, None, None)] + [(a, 22.5, None) for a in (0.0, 45.0, 90.0, 135.0)] + [
    (0.0, 22.5, 250.5),
    (90.0, 22.5, 250.5),
]


def dowd(angle, tol, band):
    ex, ey = dx[iu], dy[iu]
    dz = np.abs((z[None, :] - z[:, None])[iu])
    keep = dist < HMAX
    if angle is not None:
        u = np.array([np.cos(np.deg2rad(angle)), np.sin(np.deg2rad(angle))])
        sp = ex * u[0] + ey * u[1]
        if band is not None:
            keep &= np.hypot(ex - sp * u[0], ey - sp * u[1]) < band
        t = np.abs(sp) / dist
        keep &= (t >= 1.0) | (np.arccos(np.minimum(t, 1.0)) < np.deg2rad(tol))
    b = np.floor(dist / dh).astype(int)
    g, c = [], []
    for k in range(BINS):
        sel = dz[keep & (b == k)]
        c.append(int(sel.size))
        g.append(float(1.099 * np.median(sel) ** 2) if sel.size else 0.0)
    return g, c


for angle, tol, band in CASES:
    case = {"angle": angle, "tolerance": tol, "bandwidth": band}
    for est in ("matheron", "cressie"):
        kw = {}
        if angle is not None:
            a = np.deg2rad(angle)
            kw = dict(direction=[[np.cos(a), np.sin(a)]], angles_tol=np.deg2rad(tol))
            if band is not None:
                kw["bandwidth"] = band
        res = gs.vario_estimate((x, y), z, edges, estimator=est, return_counts=True, **kw)
        centers, gam, cnt = res
        gam = np.asarray(gam).reshape(-1)
        cnt = np.asarray(cnt).reshape(-1)
        case[est] = [float(v) for v in gam]
        case[est + "_counts"] = [int(v) for v in cnt]
        case["centers"] = [float(v) for v in centers]
    case["dowd"], case["dowd_counts"] = dowd(angle, tol, band)
    assert case["dowd_counts"] == case["matheron_counts"], case
    out["cases"].append(case)

# Fits to the omnidirectional Matheron variogram.
omni = out["cases"][0]
hc = np.array(omni["centers"])
g = np.array(omni["matheron"])
w = np.sqrt(np.array(omni["matheron_counts"], dtype=float))
mat = gs.Matern(dim=2)
mat.fit_variogram(hc, g, nugget=True, weights=w)
out["matern"] = {
    "nugget": mat.nugget,
    "sill": mat.var,
    "nu": mat.nu,
    "scale": mat.len_scale / np.sqrt(mat.nu),
}
try:
    sm = gs.Spherical(dim=2) + gs.Exponential(dim=2)
    sm.fit_variogram(hc, g, nugget=True, weights=w)
    sph, ex = sm.models
    out["nested"] = {
        "nugget": sm.nugget,
        "spherical_sill": sph.var,
        "spherical_range": sph.len_scale,
        "exponential_sill": ex.var,
        "exponential_range": 3.0 * ex.len_scale,
    }
except Exception as e:  # noqa: BLE001
    out["nested_error"] = repr(e)

with open(os.path.join(DATA, "meuse_variogram_reference.json"), "w") as f:
    json.dump(out, f, indent=1)
print(json.dumps({k: v for k, v in out.items() if k != "cases"}, indent=1))

# 3. A nested fit on generated numbers (written to tests/data/nested_fit_reference.json, not Meuse):
#    40 intervals of width 25, gamma = 0.1 + sph(0.4, 150) + exp(0.6, practical range 900) times
#    (1 + 0.03 sin(1.7 u)), counts 200 - 4 u. GSTools: Spherical + Exponential (SumModel) fitted with
#    a nugget and weights sqrt(counts); the crate: fit_nested with pair-count weights.
U = np.arange(40)
hc2 = 25.0 * (U + 0.5)


def sph(h, a):
    t = np.minimum(h / a, 1.0)
    return 1.5 * t - 0.5 * t**3


g2 = (0.1 + 0.4 * sph(hc2, 150.0) + 0.6 * (1 - np.exp(-3 * hc2 / 900.0))) * (1 + 0.03 * np.sin(1.7 * U))
c2 = 200 - 4 * U
sm2 = gs.Spherical(dim=2, len_scale=100.0) + gs.Exponential(dim=2, len_scale=300.0)
sm2.fit_variogram(hc2, g2, nugget=True, weights=np.sqrt(c2.astype(float)))
s2, e2 = sm2.models
nested = {
    "gstools": gs.__version__,
    "centers": [float(v) for v in hc2],
    "gamma": [float(v) for v in g2],
    "counts": [int(v) for v in c2],
    "nugget": sm2.nugget,
    "spherical_sill": s2.var,
    "spherical_range": s2.len_scale,
    "exponential_sill": e2.var,
    "exponential_range": 3.0 * e2.len_scale,
}
# 4. A Matérn fit with an interior smoothness on generated numbers (same file): the crate's
#    Matern(nugget 0.05, sill 1, scale 120, nu 0.8) at the same centres, times (1 + 0.02 cos(2.3 u)).
from scipy.special import gamma as gamma_fn, kv

t = hc2 / 120.0
mat_true = 0.05 + 1.0 * (1 - 2 ** (1 - 0.8) / gamma_fn(0.8) * t**0.8 * kv(0.8, t))
g3 = mat_true * (1 + 0.02 * np.cos(2.3 * U))
m3 = gs.Matern(dim=2)
m3.fit_variogram(hc2, g3, nugget=True, weights=np.sqrt(c2.astype(float)))
nested["matern"] = {
    "gamma": [float(v) for v in g3],
    "nugget": m3.nugget,
    "sill": m3.var,
    "nu": m3.nu,
    "scale": m3.len_scale / np.sqrt(m3.nu),
}
with open(os.path.join(DATA, "nested_fit_reference.json"), "w") as f:
    json.dump(nested, f, indent=1)
print(json.dumps({k: v for k, v in nested.items() if k not in ("centers", "gamma", "counts")}, indent=1))
