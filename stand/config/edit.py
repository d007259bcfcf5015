"""A configuration file changed in place: only the values that changed, the user's
comments, order and layout kept (tomlkit); ``stand calibrate`` writes with it."""

from __future__ import annotations

import tomllib

from stand.config.schema import Config, config_from_dict


def updated_toml(text: str, cfg: Config) -> str:
    """The configuration text ``text`` with only the values ``cfg`` changed from what the
    text says (its defaults included), its comments, order and layout kept (tomlkit); a
    table ``text`` lacks is added at its end."""
    import tomlkit

    doc = tomlkit.parse(text)
    before = config_from_dict(tomllib.loads(text), source="(the file updated)")[0]
    was = before.model_dump(exclude_none=True)
    for name, table in cfg.model_dump(exclude_none=True).items():
        if not isinstance(table, dict):
            if was.get(name) != table:
                doc[name] = table
            continue
        changed = {k: v for k, v in table.items() if was.get(name, {}).get(k) != v}
        if not changed:
            continue
        if name not in doc:
            doc[name] = tomlkit.table()
        for key, value in changed.items():
            doc[name][key] = value
    return tomlkit.dumps(doc)


def without_table(text: str, name: str) -> str:
    """The configuration text ``text`` without its table ``[name]`` (the rest, comments
    included, as it was); ``text`` itself when it has none."""
    import tomlkit

    doc = tomlkit.parse(text)
    if name not in doc:
        return text
    del doc[name]
    return tomlkit.dumps(doc)
