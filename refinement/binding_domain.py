"""The binding checked against its PDDL domain: every action and predicate table, every type table and the
`domain` name must be the domain's own, else a misspelt `[predicates.atbal]` would silently constrain nothing.

The names come from the domain the planner bridge has read and checked (its signature), or, where the binding
is loaded alone, from a light read of the domain file (planner_bridge's s-expression reader, no planner): its
name and the names of its predicates, actions and types. Where that read fails the check is skipped and the
planner, which parses the file for real, reports the fault with its line and column.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from tailor.errors import BindingError, TailorError

BUILTIN_TYPES = frozenset({"object"})


@dataclass(frozen=True)
class DomainVocabulary:
    """The names a binding may refer to, read from a domain file."""

    file: str
    name: str | None
    predicates: frozenset[str]
    actions: frozenset[str]
    types: frozenset[str]


def did_you_mean(name: str, known: Iterable[str]) -> str:
    """"; did you mean 'x'?" for the closest of `known` (case-insensitive), or "" when none is close: appended
    to a message, after any list of what is known."""
    by_lower = {k.lower(): k for k in sorted(known)}
    close = difflib.get_close_matches(str(name).lower(), list(by_lower), n=1, cutoff=0.6)
    return f"; did you mean '{by_lower[close[0]]}'?" if close else ""


def read_vocabulary(domain_file: Path | str) -> DomainVocabulary | None:
    """The domain's name, predicates, actions and types; None where the file cannot be read or parsed."""
    from tailor.planner_bridge.sexpr import SList, Symbol, read_sexpr

    try:
        text = Path(domain_file).read_text(encoding="utf-8-sig")
        top = read_sexpr(text, str(domain_file))
    except (OSError, UnicodeDecodeError, TailorError, RecursionError, ValueError):
        return None
    if top.head != "define":
        return None
    name, predicates, actions, types = None, set(), set(), set(BUILTIN_TYPES)
    for item in top.items[1:]:
        if not isinstance(item, SList) or not item.items:
            continue
        head, rest = item.head, item.items[1:]
        if head == "domain" and rest and isinstance(rest[0], Symbol):
            name = rest[0].text
        elif head == ":predicates":
            predicates.update(p.head for p in rest if isinstance(p, SList) and p.head)
        elif head == ":derived" and rest and isinstance(rest[0], SList) and rest[0].head:
            predicates.add(rest[0].head)
        elif head in (":action", ":durative-action") and rest and isinstance(rest[0], Symbol):
            actions.add(rest[0].text)
        elif head == ":types":
            types.update(t.text for t in rest if isinstance(t, Symbol) and t.text != "-")
    return DomainVocabulary(str(domain_file), name, frozenset(predicates), frozenset(actions), frozenset(types))


def vocabulary_of(signature) -> DomainVocabulary:
    """The vocabulary of a domain the planner bridge has read and checked already (lint.DomainSignature)."""
    return DomainVocabulary(signature.file, signature.name or None, frozenset(signature.predicates),
                            frozenset(signature.actions), frozenset(signature.types) - {"number"})


def check_against_domain(binding, vocabulary: DomainVocabulary, default_type: str) -> None:
    """A BindingError naming the binding file and the table for the first name the domain does not have."""

    def fail(message: str) -> BindingError:
        return BindingError(message, file=binding.file)

    if binding.domain is not None and vocabulary.name is not None and binding.domain.lower() != vocabulary.name:
        raise fail(f"domain = {binding.domain!r}, but {vocabulary.file} defines domain '{vocabulary.name}'")
    for kind, names, known in (("actions", binding.actions, vocabulary.actions),
                               ("predicates", binding.predicates, vocabulary.predicates)):
        for name in names:
            if name not in known:
                what = kind[:-1]
                raise fail(f"[{kind}.{name}]: domain '{vocabulary.name}' has no {what} '{name}'"
                           f"{did_you_mean(name, known)}")
    if len(vocabulary.types) > len(BUILTIN_TYPES):  # an untyped domain: any type table is the user's choice
        known = vocabulary.types | {default_type}
        for name in binding.types:
            if name.lower() not in known:
                raise fail(f"[types.{name}]: domain '{vocabulary.name}' has no type '{name}'"
                           f"{did_you_mean(name, known)}")
