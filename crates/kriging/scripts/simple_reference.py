#!/usr/bin/env python3
"""Reference simple-kriging numbers from GSTools 1.7.0 for crates/kriging/tests/simple.rs.

Prints Rust literals (predictions and kriging variances) that are pasted into the test
`simple_kriging_matches_gstools`. Run (nothing is installed into the repository):

    pip install gstools==1.7.0        # or in a venv
    python3 crates/kriging/scripts/simple_reference.py

Data: 12 deterministic 2-D points (Halton bases 2 and 3 on a 100 x 80 box), values of a smooth
field; 8 query points (one of them the sample 5, one far outside the range of every sample).

Variograms are given (no fitting), written in the kriging crate's convention and translated:

  kriging crate  nugget + sill (1 - exp(-3 h / a)) (exponential, practical range a);
                 nugget + sill (1.5 h/a - 0.5 (h/a)^3), h < a (spherical)
  GSTools        Exponential(dim=2, var=sill, len_scale=a / 3, nugget=nugget);
                 Spherical(dim=2, var=sill, len_scale=a, nugget=nugget);
                 krige.Simple(..., mean=m, exact=True, pseudo_inv=False): interpolates exactly
                 (the crate's convention), plain solve (the system is regular).
"""
import gstools as gs
import numpy as np

from gstools_points import N, lit, model, xs, ys, z

QX = np.array([10.0, 33.3, 50.0, 71.2, 90.0, xs[5], 45.0, 400.0])
QY = np.array([10.0, 60.0, 40.0, 25.5, 75.0, ys[5], 5.0, -300.0])

CASES = [
    ("exponential", 0.1, 1.0, 60.0, 2.0),
    ("spherical", 0.0, 0.8, 50.0, 1.5),
]

print(f"// gstools {gs.__version__}")
print(f"const XS: [f64; {N}] = {lit(xs)};")
print(f"const YS: [f64; {N}] = {lit(ys)};")
print(f"const Z: [f64; {N}] = {lit(z)};")
print(f"const QX: [f64; {len(QX)}] = {lit(QX)};")
print(f"const QY: [f64; {len(QY)}] = {lit(QY)};")
for name, nugget, sill, rng, mean in CASES:
    k = gs.krige.Simple(model(name, nugget, sill, rng), (xs, ys), z, mean=mean, exact=True,
                        pseudo_inv=False)
    val, var = k((QX, QY), return_var=True, mesh_type="unstructured")
    print(f"// {name}: nugget {nugget}, sill {sill}, range {rng}, mean {mean}")
    print(f"const {name.upper()}_VALUES: [f64; {len(QX)}] = {lit(val)};")
    print(f"const {name.upper()}_VARIANCES: [f64; {len(QX)}] = {lit(var)};")
