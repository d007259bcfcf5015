"""The chunked measuring path equals the all-at-once one (tests/helpers/reference_measure.py).

Tolerances: the unbalance and the phasors are the same least squares summed in
another order: 1e-11 relative (observed up to 2e-13).  The noise level comes
from single-precision side bands in both (1e-7 relative each, summed in
different orders): 1e-5 relative, and so are the 95 % radii.  The residual's
rms and the taper's cost come from the single-precision copy the first pass
keeps, or from angles computed again: 1e-6 relative.
"""

from __future__ import annotations

import functools
from dataclasses import astuple

import numpy as np
import pytest
import reference_measure

from stand.drivers.v1.build import rebuild
from stand.measuring import measure, passes
from stand.sim import load_scene, simulate


@functools.cache
def _streams(name: str, seconds: float | None = None) -> tuple[object, object]:
    sc, p, _ = load_scene(name)
    if seconds:
        data = sc.model_dump()
        data["run"]["seconds"] = seconds
        sc = type(sc).model_validate(data, strict=False)
    return rebuild(simulate(sc, p).frames), p


@pytest.mark.parametrize("keep", [passes.KEEP_BYTES, 0])
@pytest.mark.parametrize("chunk", [passes.CHUNK, 997])
@pytest.mark.parametrize("name", ["demo", "run-up", "near-resonance", "small-fast"])
@pytest.mark.parametrize("taper", [False, True])
@pytest.mark.parametrize("gate", [True, False])
def test_chunked_equals_all_at_once(
    name: str, taper: bool, gate: bool, chunk: int, keep: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With the first pass's copy (``keep``) and with the angles computed again (0)."""
    streams, p = _streams(name)
    monkeypatch.setattr(passes, "CHUNK", chunk)  # 997: many chunks, windows starting inside one
    monkeypatch.setattr(passes, "KEEP_BYTES", keep)
    new = measure.measure(streams, p, taper=taper, gate=gate)  # type: ignore[arg-type]
    old = reference_measure.measure(streams, p, taper=taper, gate=gate)  # type: ignore[arg-type]
    U0, U1 = old.solution.U_kg_m, new.solution.U_kg_m
    assert np.max(np.abs(U1 - U0) / np.abs(U0)) < 1e-11
    for a, b in zip(old.supports, new.supports, strict=True):
        assert abs(b.A_m_s2 - a.A_m_s2) < 1e-11 * abs(a.A_m_s2)
        assert b.samples == a.samples and b.revolutions == pytest.approx(a.revolutions, rel=1e-12)
        assert b.noise_m_s2 == pytest.approx(a.noise_m_s2, rel=1e-5)
        assert b.residual_m_s2 == pytest.approx(a.residual_m_s2, rel=1e-6)
        assert b.noise_cost == pytest.approx(a.noise_cost, rel=1e-6)
        for k in (2, 3):
            assert abs(b.harmonics_m_s2[k] - a.harmonics_m_s2[k]) < 1e-9 * abs(a.A_m_s2)
    assert np.allclose(new.radius95_kg_m, old.radius95_kg_m, rtol=1e-5)
    assert [w.message for w in new.warnings] == [w.message for w in old.warnings]
    # the window's place; its edge jitter is new since the reference
    # (tests/measuring/test_checks.py)
    assert [astuple(w)[:4] for w in new.windows] == [astuple(w) for w in old.windows]


@pytest.mark.parametrize("first", [0, 1, 3, 7, 12])
def test_a_window_starting_inside_a_chunk_sums_exactly_its_samples(first: int) -> None:
    """Chunks of about 5,000 samples hold two blocks: block ``first`` may start inside one."""
    from stand.core.fitsums import WindowSums, base_rows

    streams, _ = _streams("demo")
    run = passes._NodeRun(streams.nodes[1], 0.0)  # type: ignore[attr-defined]
    pos = run.pos
    n_full = (len(pos) - 1) // passes.BLOCK_REVS
    starts = run.find(pos[passes.BLOCK_REVS * np.arange(n_full + 1)])
    end = int(run.find(pos[-1:], "right")[0])
    w0 = 2 * np.pi / float(np.median(np.diff(pos)))
    saved = passes.CHUNK
    try:
        passes.CHUNK = 5000
        _, chunks, _ = passes._first_pass(run, starts, end, n_full, w0)
    finally:
        passes.CHUNK = saved
    assert len(chunks) > 4
    got = passes._window_sums(run, chunks, starts, end, first, w0)
    want = WindowSums.zero()
    _, w, a, c, s = run.chunk(int(starts[first]), end)
    want.add(base_rows(c, s, w, w0), a, w)
    assert got.n == want.n and got.w_min == want.w_min and got.w_max == want.w_max
    # sums of oscillating terms cancel to far below their parts: compare on the matrix's scale
    assert np.allclose(got.G, want.G, rtol=0, atol=1e-12 * np.abs(want.G).max())
    assert np.allclose(got.Ba, want.Ba, rtol=0, atol=1e-12 * np.abs(want.Ba).max())
