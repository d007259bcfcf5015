"""Event where clauses evaluated as OPC 10000-4 (7.7: ContentFilter, FilterOperator) says.

asyncua's server evaluates ``OfType`` as equality of the event's type with the operand,
so a client that filters on ``OfType ResultReadyEventType`` (the type *or any subtype*, as
Part 4 defines it) hears nothing of the stand's ``BalancingResultReadyEventType``, and
``OfType BaseEventType`` hears nothing at all; and a field the event does not have raises
(logged with its traceback) where Part 4 makes it NULL.  :class:`PartFourWhere` keeps
asyncua's evaluation of the other operators (Equals, IsNull, the comparisons, Not,
Between, InList, And, Or) and answers:

- ``OfType``: the event's type is the operand or one of its subtypes (HasSubtype, any
  depth, in the server's address space);
- a SimpleAttributeOperand naming a field the event lacks: NULL (None), so ``Equals`` is
  false and ``IsNull`` true, never an exception.

:func:`install` makes it the evaluator of the asyncua server in this process (asyncua
looks the class up by name in its monitored item service when a client creates an event
monitored item); the result server calls it when it starts.  The asyncua versions it was
written for are pinned in ``pyproject.toml``.
"""

from __future__ import annotations

from typing import Any

from stand.errors import UsageError

HAS_SUBTYPE = 45
"""Namespace 0's HasSubtype reference type."""


def _evaluator_base() -> Any:
    from asyncua.server import monitored_item_service

    return monitored_item_service.WhereClauseEvaluator


def part_four_where() -> type:
    """The evaluator class (built on asyncua's, imported here: heavy)."""
    from asyncua import ua

    base = _evaluator_base()

    class PartFourWhere(base):  # type: ignore[misc, valid-type]
        def _eval_el(self, index: int, event: Any) -> Any:
            el = self.elements[index]
            if el.FilterOperator == ua.FilterOperator.OfType:
                return self._of_type(event.EventType, self._eval_op(el.FilterOperands[0], event))
            return super()._eval_el(index, event)

        def _eval_op(self, op: Any, event: Any) -> Any:
            if isinstance(op, ua.SimpleAttributeOperand) and op.BrowsePath:
                return getattr(event, op.BrowsePath[-1].Name, None)  # missing: NULL
            return super()._eval_op(op, event)

        def _of_type(self, etype: Any, base_type: Any) -> bool:
            """Whether ``etype`` is ``base_type`` or a subtype of it (HasSubtype upwards)."""
            seen = set()
            while etype is not None and etype not in seen:
                if etype == base_type:
                    return True
                seen.add(etype)
                node = self._aspace.get(etype)
                refs = [] if node is None else node.references
                etype = next((r.NodeId for r in refs if not r.IsForward
                              and r.ReferenceTypeId == ua.NodeId(HAS_SUBTYPE)), None)  # fmt: skip
            return False

    return PartFourWhere


def install() -> None:
    """Make :class:`PartFourWhere` the where-clause evaluator of asyncua's server in this
    process (idempotent); an asyncua without the hook is refused naming it."""
    from asyncua.server import monitored_item_service

    current = getattr(monitored_item_service, "WhereClauseEvaluator", None)
    if current is None or not hasattr(current, "_eval_el"):
        raise UsageError("this asyncua has no WhereClauseEvaluator to extend: install the "
                         "version pyproject.toml names")  # fmt: skip
    if getattr(current, "__name__", "") != "PartFourWhere":
        monitored_item_service.WhereClauseEvaluator = part_four_where()
