"""The flexible stand against ROSS, an independent rotordynamics package (not a test).

    python3 -m venv /tmp/ross
    /tmp/ross/bin/pip install ross-rotordynamics "plotly<6"
    /tmp/ross/bin/python tests/bench/bench_ross.py

The demo stand's supports (8 and 9 kg on 45,000 and 52,000 N/m, undamped)
carry a steel shaft of 60 mm: 1.7 m bare, 1.7 m with auger flights of 12
kg/m, and 1.0 m bare; correction planes at 10 % and 90 % of the length,
5000 g mm at 30 deg and 3000 g mm at 200 deg.  In ROSS the support masses
are disks on the end nodes, the supports bearings (``kxx = C``; ``kyy`` 1e9,
stiff across the measuring plane), the flights disks on the nodes, the
shaft Rayleigh elements (rotary inertia and gyroscopic terms on, shear off:
the same beam as ours) or Timoshenko ones (shear on).  Compared: the first
three natural frequencies in the measuring plane (ROSS's nearest to ours),
and the support acceleration phasors at speeds from 0.5 x the lower
rigid-body mode to 0.8 x the first bending mode in the stand.  Prints the
README's table.  Only ``stand.core`` is imported (numpy and scipy).
"""

from __future__ import annotations

import cmath
import math
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
warnings.filterwarnings("ignore")

from stand.core import StandParameters, unbalance_from_polar  # noqa: E402
from stand.core.beam import beam_rotor, forward_beam, natural_frequencies_beam  # noqa: E402
from stand.core.shaft import Section, shaft_rotor  # noqa: E402

E, RHO, D = 2.11e11, 7810.0, 0.060
ROTORS = (("bare 1.7 m", 1.7, 0.0), ("auger 1.7 m", 1.7, 12.0), ("bare 1.0 m", 1.0, 0.0))
U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])


def ours(length: float, added: float, elements: int):  # type: ignore[no-untyped-def]
    secs = [Section(length, D, 0.0, added)]
    sup, pl = (0.0, length), (0.1 * length, 0.9 * length)
    r = shaft_rotor(secs, E, RHO, sup, pl)
    p = StandParameters(M1=8, M2=9, C1=4.5e4, C2=5.2e4, H1=0, H2=0, M3=r.M3, J3=r.J3,
                        a=r.a, b=r.b, c=r.c, d=r.d, R1=0.09, R2=0.08)  # fmt: skip
    return beam_rotor(secs, E, RHO, sup, pl, elements=elements), p


def ross_rotor(  # type: ignore[no-untyped-def]
    length: float, added: float, n: int, shear: bool, gyroscopic: bool = False
):
    import ross as rs

    steel = rs.Material(name="steel", rho=RHO, E=E, Poisson=0.29)
    h = length / n
    shaft = [
        rs.ShaftElement(L=h, idl=0.0, odl=D, material=steel, shear_effects=shear,
                        rotary_inertia=True, gyroscopic=gyroscopic)
        for _ in range(n)
    ]  # fmt: skip
    disks = [rs.DiskElement(n=0, m=8.0, Id=0.0, Ip=0.0), rs.DiskElement(n=n, m=9.0, Id=0.0, Ip=0.0)]
    for k in range(n + 1):  # the flights, as node masses
        share = added * h * (0.5 if k in (0, n) else 1.0)
        if share:
            disks.append(rs.DiskElement(n=k, m=share, Id=0.0, Ip=0.0))
    bearings = [rs.BearingElement(n=0, kxx=4.5e4, kyy=1e9, cxx=0.0),
                rs.BearingElement(n=n, kxx=5.2e4, kyy=1e9, cxx=0.0)]  # fmt: skip
    return rs.Rotor(shaft, disks, bearings)


def ross_phasors(rot, n: int, w: float) -> np.ndarray:  # type: ignore[no-untyped-def]
    res = rot.run_unbalance_response(
        node=[n // 10, 9 * n // 10],
        unbalance_magnitude=[abs(U[0]), abs(U[1])],
        unbalance_phase=[cmath.phase(U[0]), cmath.phase(U[1])],
        frequency=[w],
    )
    fr = res.forced_resp
    per = fr.shape[0] // (n + 1)  # degrees of freedom per node
    return -w * w * np.array([fr[0, 0], fr[per * n, 0]])


def main() -> None:
    n = 60
    print("| rotor | modes in the stand (ours) [Hz] | largest difference, modes | "
          "largest difference, support phasors | the same, ROSS with gyroscopic terms | "
          "Timoshenko (shear) against Rayleigh |")  # fmt: skip
    print("|---|---|---|---|---|---|")
    for name, length, added in ROTORS:
        beam, p = ours(length, added, n)
        wn = natural_frequencies_beam(beam, p, 3)
        rr = ross_rotor(length, added, n, shear=False)
        theirs = np.sort(rr.run_modal(speed=0.0, num_modes=16).wn)
        near = [theirs[np.argmin(np.abs(theirs - w))] for w in wn]
        d_modes = max(abs(a / b - 1) for a, b in zip(near, wn, strict=True))
        speeds = np.linspace(0.5 * wn[0], 0.8 * wn[2], 21)
        gy = ross_rotor(length, added, n, shear=False, gyroscopic=True)
        d_ph = d_gy = 0.0
        for w in speeds:
            if min(abs(w / x - 1) for x in wn) < 0.02:
                continue  # at a natural frequency the undamped response is unbounded
            mine = forward_beam(beam, p, float(w), U)
            for rot, which in ((rr, "plain"), (gy, "gyro")):
                d = float(np.max(np.abs(ross_phasors(rot, n, float(w)) - mine) / np.abs(mine)))
                if which == "plain":
                    d_ph = max(d_ph, d)
                else:
                    d_gy = max(d_gy, d)
        ts = ross_rotor(length, added, n, shear=True)
        tw = np.sort(ts.run_modal(speed=0.0, num_modes=16).wn)
        t_bend = tw[np.argmin(np.abs(tw - wn[2]))]
        print(
            f"| {name} | {', '.join(f'{w / (2 * math.pi):.3f}' for w in wn)} | "
            f"{d_modes:.1e} | {d_ph:.1e} | {d_gy:.1e} | first bending "
            f"{100 * (t_bend / wn[2] - 1):+.2f} % |"
        )
    print("\nmesh (ours, bare 1.7 m, first bending mode in the stand):")
    ref = None
    for m in (10, 20, 40, 60, 120, 240):
        beam, p = ours(1.7, 0.0, m)
        f = natural_frequencies_beam(beam, p, 3)[2] / (2 * math.pi)
        ref = ref or f
        print(f"  {m:4d} elements: {f:.6f} Hz")


if __name__ == "__main__":
    main()
