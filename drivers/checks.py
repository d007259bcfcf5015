"""What the data reveal about a wrong clock or a wrong mapping, for the one-clock families
(a scan module, CANopen modules): each check refuses in one line naming the figures.

- :func:`check_clock`: the recording is the clock.  The sample rate the recording shows
  (its sample indices against the receive times, a least-squares slope over the whole
  run) must agree with the configured rate within :data:`CLOCK_TOLERANCE`; a config that
  says otherwise would scale every frequency and phase wrong, so it is refused rather
  than silently replaced (the stated rate may be the one that is right and the recording
  a wrong device: a person must say which).
- :func:`check_channels`: the mark channel must be a pulse train (its samples sit near
  its two levels: few in the middle half of its range) and an accelerometer channel must
  not be one; two supports whose samples are equal frame for frame are one device fed
  to both.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.drivers.streams import RunStreams
from stand.errors import ConfigError

CLOCK_TOLERANCE = 0.01
"""A configured rate may differ from the recording's by this fraction at most (1 %)."""
MIN_CLOCK_SPAN_S = 0.5
"""Receive times shorter than this (a live session's first blocks) are not judged."""
PULSE_MIDDLE = 0.15
"""A pulse train has at most this fraction of its samples in the middle half of its range
(a mark with a 4-sample edge at 133 samples a turn: 3 %; a sine: 33 %)."""
MIN_CHANNEL_SAMPLES = 400
"""Channels with fewer samples are not judged."""
DISTINCT_POINTS = 10_000
"""Samples compared between the two supports (:func:`check_distinct`)."""
MIN_ACCEL_SPAN = 64
"""An accelerometer channel spanning fewer counts is not judged (a quiet rotor's few
counts are no pulse train; a mark input's swing spans thousands)."""


RATE_POINTS = 100_000
"""The clock's rate is judged on at most this many samples, evenly strided (its error is
receive jitter over the span, not a count: a long run's every sample adds nothing)."""


TRIM_MADS = 4.0
"""A sample whose receive time lies further than this many robust deviations (MAD) off the
clock's line is left out of the rate (:func:`recorded_rate`)."""


def clock_line(index: NDArray[np.int64], t_s: NDArray[np.float64]
               ) -> tuple[float, float] | None:  # fmt: skip
    """The clock's line: seconds a sample and the time of sample 0 [s], that the receive
    times show, or None when the span is too short.

    The least-squares line of receive time against sample index, refitted without the
    samples that lie more than :data:`TRIM_MADS` robust deviations off it: receive jitter
    and frames delivered in batches average out (a median of short spans would snap to
    the batches' lattice), and a stall of the bus (a host late on a loaded machine, then
    catching up in a burst) is left out, where a plain least-squares slope was moved by it
    (a 0.1 s stall at the start of a 2 s run: +0.65 %).  Frames lost where no counter
    tells shift the line as before (24 samples in 2 s: -0.86 %, and a warning of its own)."""
    if len(index) < 3 or float(t_s[-1] - t_s[0]) < MIN_CLOCK_SPAN_S:
        return None
    step = max(1, len(index) // RATE_POINTS)
    k, t = index[::step].astype(np.float64), t_s[::step]
    keep = np.ones(len(k), bool)
    slope, at0 = 0.0, 0.0
    for _ in range(4):
        kk, tt = k[keep] - k[keep].mean(), t[keep] - t[keep].mean()
        den = float(kk @ kk)
        if den <= 0 or int(np.count_nonzero(keep)) < 3:
            return None
        slope = float(kk @ tt) / den  # seconds per sample
        r = t - (t[keep].mean() + slope * (k - k[keep].mean()))
        mid = float(np.median(r[keep]))
        at0 = float(t[keep].mean() - slope * k[keep].mean()) + mid
        mad = 1.4826 * float(np.median(np.abs(r[keep] - mid)))
        new = np.abs(r - mid) <= max(TRIM_MADS * mad, 1e-6)
        if np.array_equal(new, keep):
            break
        keep = new
    return (slope, at0) if slope > 0 else None


def recorded_rate(index: NDArray[np.int64], t_s: NDArray[np.float64]) -> float | None:
    """The sample rate the receive times show [Hz] (:func:`clock_line`), or None when the
    span is too short."""
    line = clock_line(index, t_s)
    return None if line is None else 1.0 / line[0]


def check_clock(rate_hz: float, recorded_hz: float | None, source: str, key: str) -> None:
    """Refuse a configured ``rate_hz`` that the recording's own ``recorded_hz`` contradicts
    by more than :data:`CLOCK_TOLERANCE` (``key``: the config key that states it)."""
    if recorded_hz is None or abs(recorded_hz / rate_hz - 1.0) <= CLOCK_TOLERANCE:
        return
    raise ConfigError(
        f"the recording's clock runs at {recorded_hz:.1f} Hz, the config says "
        f"{rate_hz:g} Hz ({abs(recorded_hz / rate_hz - 1.0):.1%} apart, more than "
        f"{CLOCK_TOLERANCE:.0%}): decode it with a config of its own rate",
        source=source, key=key,
    )  # fmt: skip


def middle_fraction(v: NDArray[Any]) -> float:
    """The fraction of samples in the middle half of the channel's range (robust ends:
    the 0.5th and 99.5th percentiles)."""
    lo, hi = (float(x) for x in np.percentile(v, [0.5, 99.5]))
    if not hi > lo:
        return 0.0
    inside = (v > lo + 0.25 * (hi - lo)) & (v < lo + 0.75 * (hi - lo))
    return float(np.count_nonzero(inside)) / len(v)


def check_mark(v: NDArray[Any], name: str, source: str) -> None:
    """Refuse a mark channel that is no pulse train (an accelerometer mapped to it)."""
    if len(v) < MIN_CHANNEL_SAMPLES:
        return
    f = middle_fraction(v)
    if f > PULSE_MIDDLE:
        raise ConfigError(f"the mark channel {name} is no pulse train: {f:.0%} of its samples "
                          f"lie mid-range (a mark: under {PULSE_MIDDLE:.0%}); is an "
                          "accelerometer mapped to it?", source=source)  # fmt: skip


def check_accel(v: NDArray[Any], name: str, support: int, source: str) -> None:
    """Refuse an accelerometer channel that is a pulse train (the mark mapped to it)."""
    if len(v) < MIN_CHANNEL_SAMPLES or int(v.max()) - int(v.min()) < MIN_ACCEL_SPAN:
        return
    f = middle_fraction(v)
    if f < PULSE_MIDDLE / 3:
        raise ConfigError(f"support {support}'s accelerometer {name} reads a pulse train "
                          f"({f:.1%} of its samples mid-range): is the mark mapped to it?",
                          source=source)  # fmt: skip


def check_distinct(streams: RunStreams, source: str) -> None:
    """Refuse two supports whose samples are equal at every common index (one device's
    frames fed to both), judged on up to :data:`DISTINCT_POINTS` of support 1's samples
    spread over the run (two real accelerometers never agree on a thousand samples)."""
    a, b = streams.nodes.get(1), streams.nodes.get(2)
    if a is None or b is None or len(a.counts) < MIN_CHANNEL_SAMPLES:
        return
    if int(a.counts.max()) == int(a.counts.min()):
        return
    pick = np.arange(0, len(a.counts), max(1, len(a.counts) // DISTINCT_POINTS))
    ia, ib = np.asarray(a.index[pick]), np.asarray(b.index)
    at = np.minimum(np.searchsorted(ib, ia), len(ib) - 1)
    common = ib[at] == ia
    if np.count_nonzero(common) < MIN_CHANNEL_SAMPLES:
        return
    if np.array_equal(a.counts[pick][common], b.counts[at[common]]):
        raise ConfigError(f"supports 1 and 2 read the same samples ({np.count_nonzero(common)} "
                          "compared, equal one for one): one device's frames feed both; check "
                          "the mapping", source=source)  # fmt: skip
