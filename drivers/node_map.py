"""A run's node streams by id, some of them built only when first asked for.

A one-hour run's node takes about 0.3 s to gather from the decoded blocks and
rebuild (:func:`stand.drivers.node_build.rebuild_node`).  A solve that
measures each support in its own process (:mod:`stand.measure`) has each
process build its own node: the parent builds node 1 while a forked child
builds node 2, instead of the parent building both before the fork.  So
:func:`stand.drivers.streams.rebuild_decoded` can leave nodes *for later*:
:class:`NodeMap` holds how to build them, and builds one on first use.

Whoever uses the map sees the same streams either way: ``nodes[k]`` builds
node ``k`` here if it is still to build, and a node's warnings are those its
rebuild gives, wherever it ran (:meth:`NodeMap.built_elsewhere` records them
when a child built it; the stream itself is then built here only if asked for).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from typing import TYPE_CHECKING

from stand.core import Diagnostic

if TYPE_CHECKING:
    from stand.drivers.streams import NodeStream

Build = Callable[[], "tuple[NodeStream, list[Diagnostic]]"]
"""How to build one node's stream: the stream and its rebuild's warnings."""


class NodeMap(Mapping[int, "NodeStream"]):
    """Node streams by id (iterated in ascending order); a node left for later is built
    on first access (``nodes[k]``, ``get``, ``values``, ``items``), never by ``in``,
    ``len`` or iterating the ids."""

    def __init__(
        self,
        built: Mapping[int, tuple[NodeStream, list[Diagnostic]]],
        later: Mapping[int, tuple[Build, int]] | None = None,
    ) -> None:
        self._streams = {k: s for k, (s, _) in built.items()}
        self._warnings = {k: tuple(w) for k, (_, w) in built.items()}
        self._later = dict(later or {})
        self._ids = sorted({*self._streams, *self._later})

    def __getitem__(self, node: int) -> NodeStream:
        if node in self._later and node not in self._streams:
            stream, warnings = self._later[node][0]()
            self._streams[node] = stream
            self._warnings[node] = tuple(warnings)
        return self._streams[node]

    def __iter__(self) -> Iterator[int]:
        return iter(self._ids)

    def __len__(self) -> int:
        return len(self._ids)

    def __contains__(self, node: object) -> bool:
        return node in self._ids

    def __repr__(self) -> str:
        return f"NodeMap(built={sorted(self._streams)}, later={self.pending()})"

    def pending(self) -> list[int]:
        """The nodes not built here yet."""
        return [k for k in self._later if k not in self._streams]

    def samples_of(self, node: int) -> int:
        """The node's samples received (3 a SAMPLES frame), known without building it."""
        if node in self._streams:
            return self._streams[node].samples
        return 3 * self._later[node][1]

    def warnings_of(self, node: int) -> tuple[Diagnostic, ...]:
        """The warnings of the node's rebuild (built here now if no one has built it)."""
        if node not in self._warnings:
            self[node]
        return self._warnings[node]

    def built_elsewhere(self, node: int, warnings: tuple[Diagnostic, ...]) -> None:
        """Record the warnings a forked child's rebuild of ``node`` gave (the stream is
        built here only if asked for: the same rebuild, the same warnings)."""
        if node not in self._warnings:
            self._warnings[node] = tuple(warnings)
