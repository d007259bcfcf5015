"""The configuration: a stand, its rotor types and their corrections as TOML, validated
into frozen models (:mod:`stand.config.schema`, with the rotor's shaft in
:mod:`stand.config.rotor` and the correction's rules in :mod:`stand.config.correction`),
the stored influence matrix (:mod:`stand.config.matrix`), the values a user types
(:mod:`stand.config.typed`), where the product keeps its data
(:mod:`stand.config.paths`) and the digests the audit trail keeps of a rotor type
(:mod:`stand.config.parts`).  Bad input is one :class:`~stand.errors.ConfigError` naming
the key and the file.
"""

from stand.config.matrix import SAME_SPEED, parse_matrix, read_matrix
from stand.config.parts import CALIBRATION_KEYS, config_parts
from stand.config.paths import data_folder, rotor_types_in
from stand.config.schema import (
    STRICT,
    Config,
    config_from_dict,
    config_toml,
    default_stand_id,
    load_config,
    parse_toml,
    read_toml,
    validate,
)

__all__ = [
    "CALIBRATION_KEYS",
    "SAME_SPEED",
    "STRICT",
    "Config",
    "config_from_dict",
    "config_parts",
    "config_toml",
    "data_folder",
    "default_stand_id",
    "load_config",
    "parse_matrix",
    "parse_toml",
    "read_matrix",
    "read_toml",
    "rotor_types_in",
    "validate",
]
