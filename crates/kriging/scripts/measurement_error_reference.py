#!/usr/bin/env python3
"""Reference non-exact (measurement-error) kriging numbers from GSTools 1.7.0 for
crates/kriging/tests/measurement_error.rs.

Prints Rust literals (predictions and kriging variances) pasted into the tests
`ordinary_matches_gstools`, `simple_matches_gstools`, `duplicated_site_matches_gstools` and
`pure_nugget_matches_gstools`. Run (nothing is installed into the repository):

    pip install gstools==1.7.0        # or in a venv
    python3 crates/kriging/scripts/measurement_error_reference.py

Data: the 12 samples of scripts/simple_reference.py (Halton bases 2 and 3 on a 100 x 80 box,
values of a smooth field); 8 query points, three of them samples (0, 5 and 11), where non-exact
kriging smooths. Variograms are given (no fitting), in the kriging crate's convention translated:

  kriging crate  nugget + sill (1 - exp(-3 h / a)) (exponential, practical range a);
                 nugget + sill (1.5 h/a - 0.5 (h/a)^3), h < a (spherical)
  GSTools        Exponential(dim=2, var=sill, len_scale=a / 3, nugget=nugget);
                 Spherical(dim=2, var=sill, len_scale=a, nugget=nugget);
                 krige.Ordinary / krige.Simple(..., exact=False, cond_err="nugget",
                 pseudo_inv=False): the nugget as measurement error, plain solve (the system is
                 regular). GSTools' variance is `sill - k^T A^-1 k` with sill = nugget + var.
"""
import gstools as gs
import numpy as np

from gstools_points import N, lit, model, xs, ys, z

QX = np.array([10.0, 33.3, 50.0, 71.2, xs[0], xs[5], xs[11], 400.0])
QY = np.array([10.0, 60.0, 40.0, 25.5, ys[0], ys[5], ys[11], -300.0])

# (name, model, nugget, sill, range, mean for simple kriging)
CASES = [
    ("exponential", 0.2, 1.0, 60.0, 0.5),
    ("spherical", 0.05, 0.8, 50.0, 1.5),
]


def run(k, qx, qy):
    return k((qx, qy), return_var=True, mesh_type="unstructured")


print(f"// gstools {gs.__version__}")
print(f"const XS: [f64; {N}] = {lit(xs)};")
print(f"const YS: [f64; {N}] = {lit(ys)};")
print(f"const Z: [f64; {N}] = {lit(z)};")
print(f"const QX: [f64; {len(QX)}] = {lit(QX)};")
print(f"const QY: [f64; {len(QY)}] = {lit(QY)};")
for name, nugget, sill, rng, mean in CASES:
    m = model(name, nugget, sill, rng)
    ok = gs.krige.Ordinary(m, (xs, ys), z, exact=False, pseudo_inv=False)
    sk = gs.krige.Simple(m, (xs, ys), z, mean=mean, exact=False, pseudo_inv=False)
    up = name.upper()
    print(f"// {name}: nugget {nugget}, sill {sill}, range {rng}; simple: mean {mean}")
    for kind, k in (("OK", ok), ("SK", sk)):
        val, var = run(k, QX, QY)
        print(f"const {up}_{kind}_VALUES: [f64; {len(QX)}] = {lit(val)};")
        print(f"const {up}_{kind}_VARIANCES: [f64; {len(QX)}] = {lit(var)};")

# A site measured twice (2 and 5) plus two more samples, 1-D, exponential with nugget 0.5.
DX = np.array([0.0, 0.0, 3.0, 7.0])
DZ = np.array([2.0, 5.0, 3.0, 4.0])
DQ = np.array([0.0, 3.0, 5.0])
m = gs.Exponential(dim=1, var=1.0, len_scale=2.0, nugget=0.5)  # practical range 6
print("// duplicated site: exponential nugget 0.5, sill 1, range 6; simple mean 3")
for kind, k in (
    ("OK", gs.krige.Ordinary(m, DX, DZ, exact=False, pseudo_inv=False)),
    ("SK", gs.krige.Simple(m, DX, DZ, mean=3.0, exact=False, pseudo_inv=False)),
):
    val, var = k(DQ, return_var=True, mesh_type="unstructured")
    print(f"const DUP_{kind}_VALUES: [f64; {len(DQ)}] = {lit(val)};")
    print(f"const DUP_{kind}_VARIANCES: [f64; {len(DQ)}] = {lit(var)};")

# Pure nugget: GSTools has no zero-structure model; var=0 gives the same (zero) covariance.
m = gs.Exponential(dim=2, var=0.0, len_scale=10.0, nugget=0.3)
print("// pure nugget 0.3 (GSTools: var = 0); simple mean 0.5")
for kind, k in (
    ("OK", gs.krige.Ordinary(m, (xs, ys), z, exact=False, pseudo_inv=False)),
    ("SK", gs.krige.Simple(m, (xs, ys), z, mean=0.5, exact=False, pseudo_inv=False)),
):
    val, var = run(k, QX, QY)
    print(f"const PURE_{kind}_VALUES: [f64; {len(QX)}] = {lit(val)};")
    print(f"const PURE_{kind}_VARIANCES: [f64; {len(QX)}] = {lit(var)};")
