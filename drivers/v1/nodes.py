"""What a sensor node sends: protocol-v1 frames from samples and reference edges.

The simulated stand (and the tests) describe a node by its sample counts
and its edge positions; :func:`node_frames` turns them into the frames a
node would put on the bus, with the host timestamps they would arrive at,
and :func:`merge` interleaves several nodes by time.

Examples
--------
>>> import numpy as np
>>> f = node_frames(1, np.arange(9), rate_hz=4000, scale_um_s2=100, edges=[4.5])
>>> [hex(i) for i in f.can_id]
['0x141', '0x101', '0x181', '0x101', '0x101']
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from stand.drivers.frames import Frames
from stand.drivers.v1.codec import edge_fields, encode_marks, encode_samples, encode_status
from stand.drivers.v1.protocol import SAMPLES_PER_FRAME

STATUS_PERIOD_S = 1.0
"""A node sends STATUS at start-up, then once a second."""


def node_frames(
    node: int,
    counts: ArrayLike,
    *,
    rate_hz: float,
    scale_um_s2: int,
    edges: ArrayLike = (),
    first_seq: int = 0,
    first_rev: int = 0,
    t0_s: float = 0.0,
    status_flags: ArrayLike | None = None,
    clock_ppm: float = 0.0,
) -> Frames:
    """The frames of one node, in the order it sends them.

    Parameters
    ----------
    node
        Node id, 1..15.
    counts
        int16 sample counts from sample index ``3 * first_seq`` on; the
        length is cut to a whole number of frames.
    rate_hz
        The node's sample rate [Hz] (its own clock).
    scale_um_s2
        STATUS scale [µm/s² per count].
    edges
        Reference edges as sample positions (relative to the first sample).
    first_seq, first_rev
        Frame number of the first SAMPLES frame and revolution counter of
        the first edge (both wrap at 2**16 on the wire).
    t0_s
        Host time of sample 0 [s].
    status_flags
        Flags of each STATUS frame (one per second, the first at start-up);
        default all 0.
    clock_ppm
        The node clock's error: it really samples at
        ``rate_hz * (1 + clock_ppm * 1e-6)`` while STATUS says ``rate_hz``.

    Returns
    -------
    Frames
        SAMPLES at the time of their newest sample, MARK at the edge,
        STATUS at start-up and every second, interleaved by time.
    """
    flat = np.asarray(counts, dtype=np.int16).reshape(-1)
    n_frames = len(flat) // SAMPLES_PER_FRAME
    c = flat[: n_frames * SAMPLES_PER_FRAME].reshape(n_frames, SAMPLES_PER_FRAME)
    k = np.arange(n_frames)
    true_rate = rate_hz * (1 + clock_ppm * 1e-6)
    t_samples = t0_s + (SAMPLES_PER_FRAME * k + SAMPLES_PER_FRAME - 1) / true_rate
    samples = encode_samples(node, first_seq + k, c, t_samples)

    e = np.asarray(edges, dtype=np.float64).reshape(-1)
    e = e[(e >= 0) & (e < n_frames * SAMPLES_PER_FRAME)]
    frame, slot, frac = edge_fields(e)
    marks = encode_marks(
        node, first_seq + frame, slot, frac, first_rev + np.arange(len(e)), t0_s + e / true_rate
    )

    duration = n_frames * SAMPLES_PER_FRAME / rate_hz  # in the node's own time
    n_status = int(np.floor(duration / STATUS_PERIOD_S)) + 1
    flags = np.zeros(n_status, np.uint8) if status_flags is None else np.asarray(status_flags)
    flags = np.resize(flags, n_status)
    # just before the sample taken at the same instant, so a STATUS leads its second
    t_status = t0_s + (np.arange(n_status) * STATUS_PERIOD_S * rate_hz - 0.5) / true_rate
    status = encode_status(node, round(rate_hz), scale_um_s2, flags, t_status)
    return merge([status, samples, marks])


def merge(blocks: Sequence[Frames]) -> Frames:
    """Interleave blocks of frames by host time (stable: ties keep block order)."""
    return Frames.concat(blocks).sorted_by_time()
