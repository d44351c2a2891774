"""A small reader of PDDL's s-expressions that keeps each token's line and column, so checks can name the place."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Union

from tailor.errors import PDDLSyntaxError

# Deepest nesting of parentheses accepted. unified-planning's reader recurses once per level (and several
# frames deep), so a goal of thousands of nested (not ...) would end in a RecursionError; real domains stay
# below about 12 levels; the reader copes with about 44 from a shallow stack, 32 leaves room for a deep caller.
MAX_DEPTH = 32


@dataclass(frozen=True)
class Symbol:
    """A name, variable or keyword, lower-cased as PDDL is case-insensitive; line and col are 1-based."""

    text: str
    line: int
    col: int


@dataclass(frozen=True)
class SList:
    """A parenthesized list; line and col are those of its opening parenthesis."""

    items: tuple["Expr", ...]
    line: int
    col: int

    @property
    def head(self) -> str | None:
        """The first item's text when it is a symbol (the predicate, connective or section keyword)."""
        return self.items[0].text if self.items and isinstance(self.items[0], Symbol) else None


Expr = Union[Symbol, SList]


def read_sexpr(text: str, file: str) -> SList:
    """Read the single top-level list of a PDDL file; unbalanced parentheses are a syntax error at their place."""
    stack: list[tuple[int, int, list[Expr]]] = []
    top: list[Expr] = []
    line, col, i, n = 1, 1, 0, len(text)
    nested_section: tuple[int, int] | None = None  # first `(:keyword` found inside another section
    while i < n:
        ch = text[i]
        if ch == ";":  # a comment runs to the end of the line
            while i < n and text[i] != "\n":
                i += 1
            continue
        if ch == "\n":
            line, col, i = line + 1, 1, i + 1
            continue
        if ch.isspace():
            col, i = col + 1, i + 1
            continue
        if ch == "(":
            if len(stack) >= MAX_DEPTH:
                raise PDDLSyntaxError(
                    f"syntax error: lists nested deeper than {MAX_DEPTH} levels (the most this reader accepts)",
                    file, line, col,
                )
            stack.append((line, col, []))
        elif ch == ")":
            if not stack:
                raise PDDLSyntaxError("syntax error: unexpected ')'", file, line, col)
            start_line, start_col, items = stack.pop()
            (stack[-1][2] if stack else top).append(SList(tuple(items), start_line, start_col))
        else:
            j = i
            while j < n and not text[j].isspace() and text[j] not in "();":
                j += 1
            if nested_section is None and len(stack) >= 3 and not stack[-1][2] and ch == ":":
                nested_section = stack[-1][:2]
            (stack[-1][2] if stack else top).append(Symbol(text[i:j].lower(), line, col))
            col, i = col + (j - i), j
            continue
        col, i = col + 1, i + 1
    if stack and nested_section is not None:
        raise PDDLSyntaxError("syntax error: a ')' is missing before this section", file, *nested_section)
    if stack:
        start_line, start_col, _ = stack[-1]
        raise PDDLSyntaxError("syntax error: this '(' is never closed (a ')' is missing)", file, start_line, start_col)
    lists = [item for item in top if isinstance(item, SList)]
    if len(top) != 1 or not lists or lists[0].head != "define":
        where = top[1] if len(top) > 1 else (top[0] if top else None)
        raise PDDLSyntaxError(
            "syntax error: expected exactly one (define ...)",
            file,
            where.line if where else None,
            where.col if where else None,
        )
    return lists[0]
