"""Where the product keeps its data on this machine: one home for the user's data folder.

The default archive (``archive.sqlite``), the station's runs (``runs/``) and the
measured toolings (``tooling/``) live in it unless the config or a flag says otherwise.
"""

from __future__ import annotations

from pathlib import Path

import platformdirs


def data_folder() -> Path:
    """The user's data folder (``~/.local/share/stand`` on Linux): the default archive, the
    station's runs and the measured toolings."""
    return platformdirs.user_data_path("stand", appauthor=False)


SHIPPED_ROTORS = Path(__file__).resolve().parents[1] / "data" / "rotors"
"""The demo rotor types shipped with the product (the station's folder without
``--config-dir``): read, never changed in place."""


def rotor_types_in(folder: Path) -> list[str]:
    """The rotor types of a station's folder: its configuration files (``*.toml``), by
    name (the file's stem), sorted."""
    return sorted(p.stem for p in Path(folder).glob("*.toml") if p.is_file())
