"""mkdocs hook: the configuration and command-line references, generated at every build
from the pydantic models and the argparse parsers, so that they cannot drift from the code.

``mkdocs build --strict`` (tests/system/test_docs.py) runs it; the pages are ``reference/config.md``
and ``reference/cli.md``.
"""

from __future__ import annotations

import ast
import inspect
import itertools
import os
import textwrap
import types
import typing
from typing import Any

from mkdocs.structure.files import File
from pydantic import BaseModel


def _attribute_docs(cls: type) -> dict[str, str]:
    """Each field's docstring (the string literal after it in the class body), for the
    class and its bases."""
    out: dict[str, str] = {}
    for klass in reversed(cls.__mro__):
        if not (isinstance(klass, type) and issubclass(klass, BaseModel)) or klass is BaseModel:
            continue
        try:
            tree = ast.parse(textwrap.dedent(inspect.getsource(klass)))
        except (OSError, TypeError):
            continue
        body = tree.body[0].body  # type: ignore[attr-defined]
        for a, b in itertools.pairwise(body):
            if isinstance(a, ast.AnnAssign) and isinstance(a.target, ast.Name):
                if isinstance(b, ast.Expr) and isinstance(getattr(b, "value", None), ast.Constant):
                    out[a.target.id] = " ".join(str(b.value.value).split())
    return out


def _models(annotation: Any) -> list[type[BaseModel]]:
    """The pydantic models a field's type holds (a table, an optional table, a list of)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    out = []
    for arg in typing.get_args(annotation):
        out += _models(arg)
    return out


SYMBOLS = {
    "M1": "support 1's moving mass [kg] (the seed's symbol)",
    "M2": "support 2's moving mass [kg]",
    "C1": "support 1's stiffness along x [N/m]",
    "C2": "support 2's stiffness along x [N/m]",
    "H1": "support 1's damping [N s/m]",
    "H2": "support 2's damping [N s/m]",
    "M3": "the rotor's mass [kg]",
    "J3": "the rotor's inertia about a transverse axis through its centre of mass [kg m^2]",
    "a": "support 1 to plane 1 [m]",
    "b": "plane 1 to the centre of mass [m]",
    "c": "the centre of mass to plane 2 [m]",
    "d": "plane 2 to support 2 [m]",
    "R1": "plane 1's correction radius [m]",
    "R2": "plane 2's correction radius [m]",
    "reference_angle_deg": "where the reference sensor sees the mark [deg]",
}
"""The seed's symbols, for the keys whose meaning is their name."""

_BOUNDS = {"gt": ">", "ge": ">=", "lt": "<", "le": "<=", "min_length": "length >=",
           "max_length": "length <=", "pattern": "matches"}  # fmt: skip


def _bounds(metadata: Any) -> list[str]:
    out = []
    for m in metadata:
        for attr, word in _BOUNDS.items():
            v = getattr(m, attr, None)
            if v is not None:
                out.append(f"{word} `{v}`" if attr == "pattern" else f"{word} {v:g}")
        out += _bounds(getattr(m, "metadata", []) or [])
    return out


def _type(annotation: Any, metadata: Any = ()) -> str:
    """A type as a reader says it: ``float (> 0)``, ``list of table``, ``str or none``."""
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin is typing.Annotated:
        inner, *meta = args
        return _type(inner, [*meta, *metadata])
    if origin in (typing.Union, types.UnionType):
        names = [_type(a, metadata) for a in args if a is not type(None)]
        return " or ".join(names) + (" or none" if type(None) in args else "")
    if origin is typing.Literal:
        return " or ".join(f"`{a!r}`" for a in args)
    if origin in (list, tuple):
        return f"list of {_type(args[0]) if args else 'values'}" + _limits(metadata)
    if origin is dict:
        return f"table of {_type(args[1])}" if len(args) == 2 else "table"
    name = getattr(annotation, "__name__", str(annotation).replace("typing.", ""))
    return name + _limits(metadata)


def _limits(metadata: Any) -> str:
    b = _bounds(metadata)
    return f" ({', '.join(b)})" if b else ""


def _default(field: Any) -> str:
    if field.is_required():
        return "required"
    d = field.default
    if isinstance(d, BaseModel):
        return "(table)"
    return f"`{d!r}`" if d not in (None, [], {}) else ("none" if d is None else f"`{d!r}`")


def _table(model: type[BaseModel], name: str, lines: list[str], seen: set[str]) -> None:
    docs = _attribute_docs(model)
    sub: list[tuple[str, type[BaseModel]]] = []
    rows = []
    for key, field in model.model_fields.items():
        inner = _models(field.annotation)
        if inner:
            for m in inner:
                sub.append((f"{name}.{key}" if name else key, m))
            continue
        meaning = (docs.get(key) or SYMBOLS.get(key, "")).replace("|", "/")
        kind = _type(field.annotation, field.metadata).replace("|", "/")
        rows.append(f"| `{key}` | {kind} | {_default(field)} | {meaning} |")
    if rows:
        doc = " ".join((model.__dict__.get("__doc__") or "").split())
        lines += [f"## `[{name}]`" if name else "## top level", "", doc.replace("|", "/"), ""]
        lines += ["| key | type | default | meaning |", "|---|---|---|---|", *rows, ""]
    for sub_name, m in sub:
        key = f"{sub_name}:{m.__name__}"
        if key not in seen:
            seen.add(key)
            _table(m, sub_name, lines, seen)


def config_reference() -> str:
    from stand.config import Config
    from stand.sim import Scene

    lines = [
        "# Configuration reference",
        "",
        "Generated from the pydantic models at every build of these pages (the one home "
        "of each key). SI units inside; a key's unit is in its name or its meaning. See "
        "[Configuration](../configuration.md) for the worked example.",
        "",
        "# The stand's configuration (`--config CFG`)",
        "",
    ]
    _table(Config, "", lines, set())
    lines += ["# A scene of the simulated stand (`stand simulate SCENE`)", ""]
    lines += ["A scene holds a configuration's tables (what the stand is) and these:", ""]
    _table(Scene, "", lines, {f"{k}:{m.__name__}" for k in ("stand", "rotor", "tolerance",
                                                            "correction") for m in
                              _models(Scene.model_fields[k].annotation)})  # fmt: skip
    return "\n".join(lines) + "\n"


def cli_reference() -> str:
    from stand.cli import SUBCOMMANDS, build_parser

    os.environ["COLUMNS"] = "100"
    lines = [
        "# Command-line reference",
        "",
        "Generated from the argument parsers at every build of these pages: what `stand "
        "COMMAND --help` prints. The [Commands](../commands.md) page explains each with "
        "its figures.",
        "",
    ]
    for name, doc in SUBCOMMANDS.items():
        parser = build_parser(name)
        sub = next(a for a in parser._actions if hasattr(a, "choices") and a.choices)
        text = sub.choices[name].format_help()  # type: ignore[index]
        lines += [f"## stand {name}", "", doc, "", "```text", text.rstrip(), "```", ""]
    return "\n".join(lines)


def on_files(files: Any, config: Any) -> Any:
    for path, make in (("reference/config.md", config_reference),
                       ("reference/cli.md", cli_reference)):  # fmt: skip
        files.append(File.generated(config, path, content=make()))
    return files
