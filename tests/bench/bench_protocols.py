"""What each path from the sensors to the host costs in accuracy (not a test: run it by
hand).

    .venv/bin/python tests/bench/bench_protocols.py [--trials 40] [--seconds 2]

The demo stand at 900 rpm, the same sensor noise (0.001 m/s^2/rtHz), recorded through
protocol v1's sensor nodes at 4 kHz, through a scan-stream module (16 bit, +-10 V,
100 mV/g accelerometers, the mark on a third analog input) at 1 and 2 kHz, and through
two CANopen modules sampling on SYNC at 1 and 2 kHz, with and without 50 us of SYNC
jitter (the same inputs as the scan module's).  Per path,
Monte Carlo over seeds: support 1's 1x phasor, its spread (both components) against the
Cramer-Rao bound sqrt(2 sigma^2 / N) (sigma: the noise and the path's quantization,
q^2/12), its bias against the truth (amplitude [%], phase [deg]), and the bus load of the
path's frames (47 + 8 x bytes bits a classic frame, 17 % stuffing, at 1 Mbit/s).
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from stand.sim import load_scene, simulate
from stand.sim.scan_emit import SENSITIVITY_M_S2_PER_V, VOLTS_PER_COUNT
from stand.solve import SolveOptions, measure_streams
from stand.solve.acquisition import acquisition_of

STUFFING = 1.17
"""Bit stuffing, typical: an 8-byte classic frame's 111 bits become about 130."""


def bits(dlc: np.ndarray) -> float:
    """The bits of classic CAN frames with 11-bit ids and these data lengths, stuffed."""
    return float(np.sum((47 + 8 * dlc.astype(np.float64)) * STUFFING))


def run(protocol: str, rate: int, trials: int, seconds: float, jitter_s: float = 0.0
        ) -> dict[str, float]:  # fmt: skip
    sc, p, _ = load_scene("demo")
    sc = sc.model_copy(update={"nodes": sc.nodes.model_copy(
        update={"protocol": protocol, "rate_hz": rate, "sync_jitter_s": jitter_s})})  # fmt: skip
    cfg = sc.config()
    acq = acquisition_of(cfg, None)
    z, bits_per_s, truth = [], 0.0, 0j
    for seed in range(trials):
        run_t = sc.run.model_copy(update={"seconds": seconds, "seed": seed})
        sim = simulate(sc.model_copy(update={"run": run_t}), p)
        streams = acq.decode(sim.frames)
        z.append(measure_streams(streams, cfg, p, SolveOptions()).supports[0].A_m_s2)
        bits_per_s = bits(sim.frames.dlc) / seconds
        truth = complex(sim.truth["A_m_s2"][0])  # type: ignore[index]
    zz = np.array(z)
    q = (VOLTS_PER_COUNT * SENSITIVITY_M_S2_PER_V if protocol != "v1"
         else sc.nodes.scale_um_s2 * 1e-6)  # fmt: skip
    sigma2 = (0.001 * math.sqrt(rate / 2)) ** 2 + q**2 / 12
    bound = math.sqrt(2 * sigma2 / (seconds * rate))
    mean = zz.mean()
    return {
        "spread_re": float(np.std(zz.real, ddof=1) / bound),
        "spread_im": float(np.std(zz.imag, ddof=1) / bound),
        "bias_pct": float(100 * (abs(mean) - abs(truth)) / abs(truth)),
        "bias_deg": float(math.degrees(np.angle(mean / truth))),
        "bound_m_s2": bound,
        "load_pct": 100 * bits_per_s / 1e6,
    }


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--trials", type=int, default=40)
    ap.add_argument("--seconds", type=float, default=2.0)
    a = ap.parse_args()
    print("| path | spread / bound (Re, Im) | bias amplitude | bias phase | bound | bus load |")
    print("|---|---|---|---|---|---|")
    names = {"v1": "protocol v1, two nodes", "scan": "scan module",
             "canopen": "CANopen on SYNC"}  # fmt: skip
    for protocol, rate, jitter in (("v1", 4000, 0.0), ("scan", 1000, 0.0), ("scan", 2000, 0.0),
                                   ("canopen", 1000, 0.0), ("canopen", 2000, 0.0),
                                   ("canopen", 1000, 50e-6), ("canopen", 2000, 50e-6)):  # fmt: skip
        r = run(protocol, rate, a.trials, a.seconds, jitter)
        name = names[protocol] + (f", {jitter * 1e6:g} us jitter" if jitter else "")
        print(f"| {name} at {rate / 1000:g} kHz | {r['spread_re']:.2f}, {r['spread_im']:.2f} "
              f"| {r['bias_pct']:+.4f} % | {r['bias_deg']:+.4f} deg | "
              f"{1000 * r['bound_m_s2']:.3f} mm/s^2 | {r['load_pct']:.0f} % |")  # fmt: skip


if __name__ == "__main__":
    main()
