"""The simulator's hardware: one entry a family of the drivers' registry, chosen in one
place; a scene's ``[nodes]`` takes the same CAN FD rule as ``[bus.scan]``."""

from __future__ import annotations

from typing import get_args

import pytest
from pydantic import ValidationError

from stand.drivers.family import FAMILIES
from stand.sim.hardware import SIMULATED, simulated
from stand.sim.tables import NodesTable


def test_every_family_has_simulated_hardware_and_a_scene_can_name_it() -> None:
    names = set(get_args(NodesTable.model_fields["protocol"].annotation))
    assert set(SIMULATED) == set(FAMILIES) == names
    assert all(simulated(n).name == n for n in SIMULATED)


@pytest.mark.parametrize(("k", "ok"), [(1, True), (2, True), (3, True), (4, True), (5, False),
                                       (6, True), (7, False), (8, True)])  # fmt: skip
def test_scans_per_frame_by_the_can_fd_lengths(k: int, ok: bool) -> None:
    if ok:
        assert NodesTable(scans_per_frame=k).scans_per_frame == k
    else:
        with pytest.raises(ValidationError, match="not a CAN FD payload length"):
            NodesTable(scans_per_frame=k)
