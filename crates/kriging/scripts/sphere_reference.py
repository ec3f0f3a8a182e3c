#!/usr/bin/env python3
"""Reference numbers for crates/kriging/tests/sphere.rs (issue 37, item 5) from GSTools 1.7.0.

Prints Rust literals pasted into the test. Run (nothing is installed into the repository):

    pip install gstools==1.7.0        # or in a venv
    python3 crates/kriging/scripts/sphere_reference.py

Data: 20 deterministic points in latitude/longitude degrees (Halton bases 2 and 3: latitude in
[35, 65], longitude in [-15, 35]), values of a smooth field; 6 query points (one of them sample 4).

1. Kriging with `latlon=True`: GSTools places the points on a sphere of radius `geo_scale`
   (`latlon2pos`) and uses the chordal (straight-line) distance there; `len_scale` is in the units
   of `geo_scale`. Here `geo_scale = gs.EARTH_RADIUS` (6371 km), Exponential(latlon=True,
   var=0.8, len_scale=1500/3, nugget=0.05) (practical range 1500 km in the crate's convention),
   `krige.Ordinary(..., exact=True)` and `krige.Simple(..., mean=1.0, exact=True)`; predictions and
   kriging variances at the queries.
2. Empirical variogram with `latlon=True, geo_scale=gs.EARTH_RADIUS`: GSTools bins the great-circle
   (haversine) distance times the radius: 8 intervals up to 2400 km.
"""
import gstools as gs
import numpy as np


def radical(i, b):
    f, r = 1.0, 0.0
    while i > 0:
        f /= b
        r += f * (i % b)
        i //= b
    return r


def lit(a):
    return "[" + ", ".join(repr(float(v)) for v in a) + "]"


N = 20
lat = np.array([35.0 + 30.0 * radical(i, 2) for i in range(1, N + 1)])
lon = np.array([-15.0 + 50.0 * radical(i, 3) for i in range(1, N + 1)])
z = np.sin(np.deg2rad(lat) * 4.0) + 0.5 * np.cos(np.deg2rad(lon) * 3.0) + 0.01 * lon
QLAT = np.array([50.0, 40.0, 62.5, lat[4], 55.0, 30.0])
QLON = np.array([10.0, 0.0, 25.0, lon[4], -20.0, 40.0])

R = gs.EARTH_RADIUS
model = gs.Exponential(latlon=True, var=0.8, len_scale=1500.0 / 3.0, nugget=0.05, geo_scale=R)
ok = gs.krige.Ordinary(model, (lat, lon), z, exact=True, pseudo_inv=False)
ok_v, ok_s = ok((QLAT, QLON), mesh_type="unstructured", return_var=True)
sk = gs.krige.Simple(model, (lat, lon), z, mean=1.0, exact=True, pseudo_inv=False)
sk_v, sk_s = sk((QLAT, QLON), mesh_type="unstructured", return_var=True)

edges = np.linspace(0.0, 2400.0, 9)
centers, gam, cnt = gs.vario_estimate((lat, lon), z, edges, latlon=True, geo_scale=R, return_counts=True)

print(f"// gstools {gs.__version__}, EARTH_RADIUS = {R!r}")
print(f"const LAT: [f64; {N}] = {lit(lat)};")
print(f"const LON: [f64; {N}] = {lit(lon)};")
print(f"const Z: [f64; {N}] = {lit(z)};")
print(f"const QLAT: [f64; 6] = {lit(QLAT)};")
print(f"const QLON: [f64; 6] = {lit(QLON)};")
print(f"const OK_VALUE: [f64; 6] = {lit(ok_v)};")
print(f"const OK_VAR: [f64; 6] = {lit(ok_s)};")
print(f"const SK_VALUE: [f64; 6] = {lit(sk_v)};")
print(f"const SK_VAR: [f64; 6] = {lit(sk_s)};")
print(f"const VARIO: [f64; 8] = {lit(gam)};")
print(f"const VARIO_COUNTS: [usize; 8] = [{', '.join(str(int(c)) for c in cnt)}];")
