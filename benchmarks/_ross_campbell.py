"""Time ROSS's run_campbell on the Table 2 rotor with method-A bearings (k = 1e6 N/m, no damping).

Usage: python _ross_campbell.py REPEAT N1 [N2 ...]. Run by benchmarks/linear.py in an interpreter that has
ross-rotordynamics (Python >= 3.12); ``build_rotor`` is also used by tests/reference/make_ross_campbell.py.
Prints one JSON line: {"version", "times_s": {n_speeds: best wall time}, "freq_hz_100krpm": [...]}.
"""
import json
import sys
import time
import warnings

import numpy as np

warnings.filterwarnings("ignore")


def build_rotor(kx=1e6, ky=None):
    """The Table 2 rotor in ROSS on undamped springs ``kx``, ``ky`` [N/m] at nodes 1 and 2 (``ky = kx`` if None).

    3 Euler-Bernoulli shaft elements (33, 39, 33 mm, d = 11 mm) with rotary inertia and gyroscopic terms and
    no shear, the turbine and compressor wheels as rigid discs at nodes 0 and 3
    (docs/theory/equations-of-motion.md#euler-bernoulli-shaft-element, parameters.md#table-2-in-si-units).
    """
    import ross as rs

    ky = kx if ky is None else ky
    steel = rs.Material(name="frb_steel", rho=7860.0, E=2e11, Poisson=0.3)
    shaft = [rs.ShaftElement(L=l, idl=0.0, odl=0.011, material=steel, shear_effects=False, rotary_inertia=True,
                             gyroscopic=True) for l in (0.033, 0.039, 0.033)]
    disks = [rs.DiskElement(n=0, m=0.326, Id=7.7e-5, Ip=8.1e-5), rs.DiskElement(n=3, m=0.118, Id=3.27e-5, Ip=4.4e-5)]
    bearings = [rs.BearingElement(n=n, kxx=kx, kyy=ky, cxx=0.0) for n in (1, 2)]
    return rs.Rotor(shaft, disks, bearings)


def main(counts, repeat):
    import ross as rs

    rotor = build_rotor()
    out = {"version": rs.__version__, "times_s": {}}
    for n in counts:
        speeds = np.linspace(10e3, 250e3, n) * np.pi / 30
        best = np.inf
        rotor.run_campbell(speeds[:2], frequencies=8)  # warm-up
        for _ in range(repeat if n <= 50 else 1):
            t0 = time.perf_counter()
            rotor.run_campbell(speeds, frequencies=8)
            best = min(best, time.perf_counter() - t0)
        out["times_s"][str(n)] = best
    modal = rotor.run_modal(speed=100e3 * np.pi / 30, num_modes=16)
    out["freq_hz_100krpm"] = sorted(float(f) for f in np.asarray(modal.wd) / (2 * np.pi))[:8]
    print(json.dumps(out))


if __name__ == "__main__":
    args = [int(x) for x in sys.argv[1:]]
    main(args[1:] or [26], args[0] if args else 5)
