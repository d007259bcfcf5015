"""Configs of bending rotors for tests: the demo stand with a shaft of a given length and
added mass a metre, the 1.7 m auger's shaft table, and its rigid twin (the auger's rigid
values, no shaft)."""

from __future__ import annotations

import re
from pathlib import Path

from stand.core.shaft import Section, shaft_rotor

ROOT = Path(__file__).resolve().parents[2]


def shaft_config(folder: Path, length: float, added: float, *, extra: str = "") -> Path:
    text = (ROOT / "examples" / "demo-stand.toml").read_text()
    head, rest = text.split("[rotor]\n", 1)
    kept = [ln for ln in rest.splitlines() if ln.split("=")[0].strip() not in "M3 J3 a b c d"]
    table = (
        "[rotor.shaft]\nE_pa = 2.11e11\ndensity_kg_m3 = 7810.0\n"
        f"sections = [ {{ length_m = {length}, diameter_m = 0.060, added_kg_m = {added} }} ]\n"
        f"support_positions_m = [0.0, {length}]\n"
        f"plane_positions_m = [{0.1 * length}, {0.9 * length}]\n"
    )
    path = folder / f"shaft-{length}-{added}.toml"
    path.write_text(head + "[rotor]\n" + extra + "\n".join(kept) + "\n" + table)
    return path


SHAFT = (
    "[rotor.shaft]\nE_pa = 2.11e11\ndensity_kg_m3 = 7810.0\n"
    "sections = [ { length_m = 1.7, diameter_m = 0.060, added_kg_m = 12.0 } ]\n"
    "support_positions_m = [0.0, 1.7]\nplane_positions_m = [0.17, 1.53]\n\n"
)


def rigid_twin(folder: Path) -> Path:
    """The demo config with the auger's rigid values (M3, J3, a..d) and no shaft."""
    r = shaft_rotor([Section(1.7, 0.06, 0.0, 12.0)], 2.11e11, 7810.0, (0.0, 1.7), (0.17, 1.53))
    text = (ROOT / "examples" / "demo-stand.toml").read_text()
    for k in ("M3", "J3", "a", "b", "c", "d"):
        text = re.sub(rf"^{k} = [0-9.e+-]+", f"{k} = {getattr(r, k)!r}", text, count=1, flags=re.M)
    path = folder / "rigid.toml"
    path.write_text(text)
    return path
