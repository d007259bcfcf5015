"""What happens to any simulated hardware's samples and frames on their way, whatever the
family: each effect draws from its own random stream (``numpy.random.default_rng([seed,
effect, node])``), so naming one effect changes no byte another produced; the sensor's
white noise; frames lost on the bus, single or in bursts."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from stand.drivers.frames import Frames

_STREAM = {
    name: i
    for i, name in enumerate(
        ("noise", "edge_jitter", "lost_frames", "invalid", "bursts", "sync_jitter", "canopen")
    )
}


def rng_of(scene: Any, effect: str, node: int = 0) -> np.random.Generator:
    """The random stream of one effect at one node."""
    return np.random.default_rng([scene.run.seed, _STREAM[effect], node])


def noisy(scene: Any, node: int, a: Any) -> Any:
    """The sensor's white noise added to the acceleration ``a`` node ``node`` reads [m/s^2]
    (the scene's ``[effects.noise]``; the same draw whatever carries the samples)."""
    e = scene.effects
    if not e.noise:
        return a
    rms = (
        e.noise.rms_m_s2
        if e.noise.rms_m_s2 is not None
        else e.noise.density_m_s2_rthz * math.sqrt(scene.nodes.rate_hz / 2)
    )
    return a + rng_of(scene, "noise", node).normal(0.0, rms, len(a))


def lost(scene: Any, node: int, frames: Frames) -> Frames:
    """Frames lost on the bus: single ones and bursts."""
    lf = scene.effects.lost_frames
    if lf is None:
        return frames
    keep = np.ones(len(frames), bool)
    if lf.probability > 0:
        keep &= rng_of(scene, "lost_frames", node).random(len(frames)) >= lf.probability
    if lf.bursts_per_s > 0 and len(frames):
        rng = rng_of(scene, "bursts", node)
        duration = float(frames.t_s[-1] - frames.t_s[0])
        n = rng.poisson(lf.bursts_per_s * duration)
        for s in rng.integers(0, len(frames), n).tolist():
            keep[s : s + lf.burst_frames] = False
    return frames.take(keep)
