"""The 12 sample points, their values and the variogram translation shared by the GSTools
reference scripts (simple_reference.py, measurement_error_reference.py): imported, not run.

Data: 12 deterministic 2-D points (Halton bases 2 and 3 on a 100 x 80 box), values of a smooth
field. Variograms in the kriging crate's convention, translated to GSTools:

  kriging crate  nugget + sill (1 - exp(-3 h / a)) (exponential, practical range a);
                 nugget + sill (1.5 h/a - 0.5 (h/a)^3), h < a (spherical)
  GSTools        Exponential(dim=2, var=sill, len_scale=a / 3, nugget=nugget);
                 Spherical(dim=2, var=sill, len_scale=a, nugget=nugget)
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


N = 12
xs = np.array([100.0 * radical(i, 2) for i in range(1, N + 1)])
ys = np.array([80.0 * radical(i, 3) for i in range(1, N + 1)])
z = np.sin(xs / 30.0) + 0.5 * np.cos(ys / 20.0) + 0.01 * xs


def model(name, nugget, sill, rng):
    if name == "exponential":
        return gs.Exponential(dim=2, var=sill, len_scale=rng / 3.0, nugget=nugget)
    return gs.Spherical(dim=2, var=sill, len_scale=rng, nugget=nugget)


def lit(a):
    return "[" + ", ".join(repr(float(v)) for v in a) + "]"
