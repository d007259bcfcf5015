"""Sentences for people, marked for the catalogues where the engine writes them.

The engine (the core, the drivers, measuring, solving, health) writes what it tells a
person in English, through :func:`said`: the message (a template with ``{name}``
placeholders, the text the catalogues ``stand/data/locale`` translate) and its values.
The sentence stays plain English text wherever it goes (the run file, the archive, the
JSON); a screen, the certificate or the operator's CLI text in another language finds
the message again from the sentence and translates it with its values
(:meth:`stand.i18n.language.Language.__call__`), so an archived run's warnings read
in the reader's language too.  :func:`N_` marks a word that is named here and shown
elsewhere.
"""

from __future__ import annotations


def N_(msgid: str) -> str:
    """Mark a message for the catalogues where it is named, not shown (no translation)."""
    return msgid


def said(msgid: str, /, **values: object) -> str:
    """The English sentence of message ``msgid`` with its ``{name}`` placeholders filled
    (each value as ``str`` gives it: format a number before, ``f"{x:.1f}"``).

    Examples
    --------
    >>> said("node {node}: {n} frames lost", node=1, n=3)
    'node 1: 3 frames lost'
    """
    return msgid.format(**values)
