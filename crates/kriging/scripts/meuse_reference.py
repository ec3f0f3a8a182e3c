#!/usr/bin/env python3
"""Reference kriging numbers on the Meuse data (log zinc) from PyKrige 1.7.3 and GSTools 1.7.0.

Writes crates/kriging/tests/data/meuse_reference.json, read by crates/kriging/tests/meuse.rs.

Run (from the repository root; nothing is installed into the repository):

    python3 -m venv /tmp/kvenv
    /tmp/kvenv/bin/pip install pykrige==1.7.3 gstools==1.7.0
    /tmp/kvenv/bin/python crates/kriging/scripts/meuse_reference.py

Data: crates/kriging/tests/data/meuse.csv (x, y, zinc; 155 points), taken from scikit-gstat 1.0.26
(skgstat/data/samples/meuse.txt), which took it from the R package sp; GPL-3 (see MEUSE_SOURCE.md).

Variograms are *given* (no fitting), so that the three implementations solve the same system.
Every variogram below is written in the kriging crate's convention and translated for each library:

  kriging crate  Variogram { model, nugget, sill (partial sill), range }      gamma(0) = 0,
                 spherical:   nugget + sill (1.5 h/a - 0.5 (h/a)^3) for 0 < h < a, nugget + sill beyond
                 exponential: nugget + sill (1 - exp(-3 h / a))    (a = practical range)
  PyKrige        variogram_parameters = {"psill": sill, "range": a, "nugget": nugget};
                 its "exponential" is psill (1 - exp(-h / (range / 3))) + nugget: the same practical
                 range. exact_values=True (default): the nugget is a jump at h > 0, predictions are
                 exact at the samples and the variance there is 0. The returned variance `ss` is the
                 kriging variance sigma^2 = sum_i lambda_i gamma(x, x_i) + mu (Lagrange terms).
  GSTools        Spherical(dim=2, var=sill, len_scale=a, nugget=nugget);
                 Exponential(dim=2, var=sill, len_scale=a / 3, nugget=nugget) (cov = var exp(-h / len_scale));
                 Krige(..., exact=True) so that it interpolates like PyKrige and the crate;
                 pseudo_inv=False (plain inverse: the system is regular).

Drifts: "linear" = 1, x, y (PyKrige "regional_linear", GSTools drift_functions="linear");
"quadratic" = 1, x, y, x^2, x y, y^2 (PyKrige functional drift, GSTools drift_functions="quadratic");
"external" = 1 plus one external variable e(x, y) = sqrt((x - 179000)^2 + (y - 331000)^2) / 1000
(PyKrige "specified", GSTools ext_drift), which the Rust test recomputes with the same formula.
"""

import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "tests", "data")


def load():
    raw = np.loadtxt(os.path.join(DATA, "meuse.csv"), delimiter=",", skiprows=1)
    return raw[:, 0], raw[:, 1], np.log(raw[:, 2])


def ext(x, y):
    return np.sqrt((x - 179000.0) ** 2 + (y - 331000.0) ** 2) / 1000.0


def query_points(x, y):
    """Fixed points: a 6 x 6 grid over the bounding box, ten scattered points, two samples."""
    gx = np.linspace(x.min(), x.max(), 6)
    gy = np.linspace(y.min(), y.max(), 6)
    qx, qy = np.meshgrid(gx, gy, indexing="xy")
    qx, qy = list(qx.ravel()), list(qy.ravel())
    scattered = [
        (179500.0, 331500.0), (180000.0, 332000.0), (180500.0, 332500.0), (179100.0, 330200.0),
        (181000.0, 333000.0), (178700.0, 330800.0), (179850.0, 331150.0), (180250.0, 331900.0),
        (180800.0, 333400.0), (178900.0, 329900.0),
    ]
    for a, b in scattered:
        qx.append(a)
        qy.append(b)
    for i in (0, 77):  # exactly at samples: prediction = data, variance = 0
        qx.append(float(x[i]))
        qy.append(float(y[i]))
    return np.array(qx), np.array(qy)


CASES = [
    # name, model, drift, nugget, sill (partial), range (practical)
    ("ok_spherical", "spherical", "none", 0.05, 0.59, 897.0),
    ("ok_exponential", "exponential", "none", 0.04, 0.62, 1200.0),
    ("uk_linear_spherical", "spherical", "linear", 0.05, 0.5, 800.0),
    ("uk_quadratic_exponential", "exponential", "quadratic", 0.03, 0.45, 900.0),
    ("ked_spherical", "spherical", "external", 0.05, 0.5, 850.0),
]


def pykrige_case(x, y, z, qx, qy, model, drift, nugget, sill, rng):
    from pykrige.ok import OrdinaryKriging
    from pykrige.uk import UniversalKriging

    params = {"psill": sill, "range": rng, "nugget": nugget}
    if drift == "none":
        k = OrdinaryKriging(x, y, z, variogram_model=model, variogram_parameters=params)
        zz, ss = k.execute("points", qx, qy, backend="vectorized")
    elif drift == "linear":
        k = UniversalKriging(x, y, z, variogram_model=model, variogram_parameters=params,
                             drift_terms=["regional_linear"])
        zz, ss = k.execute("points", qx, qy, backend="vectorized")
    elif drift == "quadratic":
        fns = [lambda a, b: a, lambda a, b: b, lambda a, b: a * a, lambda a, b: a * b,
               lambda a, b: b * b]
        # Functional drift on raw coordinates ~1.8e5 makes PyKrige's system badly scaled; centre the
        # coordinates first (the quadratic drift space, with the constant, is invariant under the
        # shift, so the kriging predictor is the same).
        cx, cy = 180000.0, 331500.0
        k = UniversalKriging(x - cx, y - cy, z, variogram_model=model, variogram_parameters=params,
                             drift_terms=["functional"], functional_drift=fns)
        zz, ss = k.execute("points", qx - cx, qy - cy, backend="vectorized")
    elif drift == "external":
        k = UniversalKriging(x, y, z, variogram_model=model, variogram_parameters=params,
                             drift_terms=["specified"], specified_drift=[ext(x, y)])
        zz, ss = k.execute("points", qx, qy, backend="vectorized",
                           specified_drift_arrays=[ext(qx, qy)])
    else:
        raise ValueError(drift)
    return np.asarray(zz, dtype=float), np.asarray(ss, dtype=float)


def gstools_case(x, y, z, qx, qy, model, drift, nugget, sill, rng):
    import gstools as gs

    if model == "spherical":
        m = gs.Spherical(dim=2, var=sill, len_scale=rng, nugget=nugget)
    else:
        m = gs.Exponential(dim=2, var=sill, len_scale=rng / 3.0, nugget=nugget)
    kw = dict(exact=True, pseudo_inv=False)
    cx, cy = 180000.0, 331500.0  # centred as for PyKrige (drift functions see the coordinates)
    pos = (x - cx, y - cy)
    qpos = (qx - cx, qy - cy)
    if drift == "none":
        k = gs.krige.Ordinary(m, pos, z, **kw)
        f, v = k(qpos, mesh_type="unstructured")
    elif drift in ("linear", "quadratic"):
        k = gs.krige.Universal(m, pos, z, drift_functions=drift, **kw)
        f, v = k(qpos, mesh_type="unstructured")
    else:
        k = gs.krige.ExtDrift(m, pos, z, ext_drift=ext(x, y), **kw)
        f, v = k(qpos, mesh_type="unstructured", ext_drift=ext(qx, qy))
    return np.asarray(f, dtype=float), np.asarray(v, dtype=float)


def main():
    import gstools
    import pykrige

    x, y, z = load()
    qx, qy = query_points(x, y)
    out = {
        "about": "Reference kriging of log(zinc) on Meuse; produced by crates/kriging/scripts/"
                 "meuse_reference.py. Variogram parameters in the kriging crate's convention "
                 "(partial sill, practical range).",
        "pykrige_version": pykrige.__version__,
        "gstools_version": gstools.__version__,
        "numpy_version": np.__version__,
        "query_x": list(map(float, qx)),
        "query_y": list(map(float, qy)),
        "cases": [],
    }
    worst = 0.0
    for name, model, drift, nugget, sill, rng in CASES:
        pz, ps = pykrige_case(x, y, z, qx, qy, model, drift, nugget, sill, rng)
        gz, gv = gstools_case(x, y, z, qx, qy, model, drift, nugget, sill, rng)
        dz = float(np.max(np.abs(pz - gz)))
        dv = float(np.max(np.abs(ps - gv)))
        worst = max(worst, dz, dv)
        print(f"{name:28s} |PyKrige - GSTools|: prediction {dz:.2e}, variance {dv:.2e}")
        out["cases"].append({
            "name": name, "model": model, "drift": drift,
            "nugget": nugget, "sill": sill, "range": rng,
            "pykrige_prediction": list(map(float, pz)),
            "pykrige_variance": list(map(float, ps)),
            "gstools_prediction": list(map(float, gz)),
            "gstools_variance": list(map(float, gv)),
        })
    path = os.path.join(DATA, "meuse_reference.json")
    with open(path, "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")
    print(f"wrote {path}; largest PyKrige/GSTools disagreement {worst:.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
