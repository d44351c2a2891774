"""What refinement minimizes and keeps within bounds (Ch. 8.1): a weighted sum of measures, and limits on them.

An objective is written as a sum of terms, each a measure, or a measure times a weight (either way round):

    objective := term ("+" term)*
    term      := MEASURE | NUMBER "*" MEASURE | MEASURE "*" NUMBER
    MEASURE   := [A-Za-z_][A-Za-z0-9_]*         (duration, energy, error, heading_error, ...)
    NUMBER    := 12 | 0.3 | .5 | 1e-3           (finite, >= 0)

e.g. `duration + 0.3*energy`. A measure written twice has the sum of its weights. A limit is `MEASURE=NUMBER`
(`error=0.05`: every action's predicted error at most 0.05 m). A small tokenizer and a recursive-descent parser
read them, never `eval`: any other text is an ObjectiveSyntaxError naming the column (1-based) and what was
expected there. Which measures exist, and whether every action has a model of each, is checked where the
models are known (refinement.measures).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

DURATION = "duration"  # the measure every action model predicts (Chapter 4)
MAX_TEXT = 1000  # characters of an objective or a limit: more is no objective anyone writes
_TOKEN = re.compile(r"""
    (?P<space>\s+)
  | (?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)
  | (?P<name>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<plus>\+) | (?P<times>\*) | (?P<minus>-) | (?P<equals>=)
""", re.VERBOSE)
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_SHOWN = {"number": "a number", "name": "a measure", "plus": "'+'", "times": "'*'", "minus": "'-'",
          "equals": "'='", "end": "the end"}


class ObjectiveSyntaxError(ValueError):
    """An objective or limit that does not parse; `col` is the 1-based column of the fault (None: the whole)."""

    def __init__(self, message: str, col: int | None = None):
        super().__init__(message if col is None else f"col {col}: {message}")
        self.col = col


@dataclass(frozen=True)
class Token:
    kind: str  # number, name, plus, times, minus, equals, end
    text: str
    col: int  # 1-based

    def shown(self) -> str:
        """The token as an error message names it: `a number '0.3'`, `a measure 'energy'`, `'+'`, `the end`."""
        if self.kind in ("number", "name"):
            return f"{_SHOWN[self.kind]} {self.text!r}"
        return _SHOWN[self.kind]


def tokenize(text: str) -> list[Token]:
    """The tokens of `text`, ending in an `end` token; an ObjectiveSyntaxError at the first character that
    starts none."""
    if not isinstance(text, str):
        raise ObjectiveSyntaxError(f"expected text, not {type(text).__name__}")
    if len(text) > MAX_TEXT:
        raise ObjectiveSyntaxError(f"longer than {MAX_TEXT} characters")
    tokens, at = [], 0
    while at < len(text):
        match = _TOKEN.match(text, at)
        if match is None:
            raise ObjectiveSyntaxError(f"unexpected character {text[at]!r}", at + 1)
        if match.lastgroup != "space":
            tokens.append(Token(match.lastgroup, match.group(), at + 1))
        at = match.end()
    tokens.append(Token("end", "", len(text) + 1))
    return tokens


@dataclass(frozen=True)
class WeightedObjective:
    """Sum of weight * predicted measure over the actions of a window: `weights` as (measure, weight) pairs in
    the order first written, every weight finite and >= 0, at least one > 0."""

    weights: tuple[tuple[str, float], ...]

    def __post_init__(self) -> None:
        names = [m for m, _ in self.weights]
        if len(set(names)) != len(names):
            raise ValueError(f"a measure weighed twice in {self.weights}")
        for measure, weight in self.weights:
            if not _NAME.match(measure):
                raise ValueError(f"{measure!r} is not a measure's name")
            if not (math.isfinite(weight) and weight >= 0):
                raise ValueError(f"the weight of {measure} must be a finite number >= 0, not {weight!r}")
        if not any(w > 0 for _, w in self.weights):
            raise ValueError("the objective weighs no measure (every weight is 0)")

    @property
    def measures(self) -> tuple[str, ...]:
        """The measures with a weight above 0: those whose models are summed."""
        return tuple(m for m, w in self.weights if w > 0)

    def weight(self, measure: str) -> float:
        return dict(self.weights).get(measure, 0.0)

    @property
    def plain(self) -> bool:
        """Whether this is the dissertation's objective, the predicted duration alone (weight 1)."""
        return self.weights == ((DURATION, 1.0),)

    def text(self) -> str:
        """The objective written back in the grammar above: `duration + 0.3*energy`."""
        return " + ".join(m if w == 1 else f"{w:g}*{m}" for m, w in self.weights if w > 0)

    def to_json(self) -> dict[str, float]:
        return {m: w for m, w in self.weights}


DURATION_ONLY = WeightedObjective(((DURATION, 1.0),))


@dataclass(frozen=True)
class MeasureBound:
    """A limit on every action's predicted measure: `measure` <= `bound` (in the measure's unit)."""

    measure: str
    bound: float

    def __post_init__(self) -> None:
        if not _NAME.match(self.measure):
            raise ValueError(f"{self.measure!r} is not a measure's name")
        if not (math.isfinite(self.bound) and self.bound >= 0):
            raise ValueError(f"the bound of {self.measure} must be a finite number >= 0, not {self.bound!r}")

    def text(self) -> str:
        return f"{self.measure}={self.bound:g}"


class _Parser:
    """Recursive descent over the tokens of one objective (the module's grammar)."""

    def __init__(self, text: str):
        self.tokens = tokenize(text)
        self.at = 0

    @property
    def token(self) -> Token:
        return self.tokens[self.at]

    def take(self, kind: str) -> Token | None:
        if self.token.kind == kind:
            self.at += 1
            return self.tokens[self.at - 1]
        return None

    def fail(self, expected: str) -> ObjectiveSyntaxError:
        token = self.token
        if token.kind == "minus":
            return ObjectiveSyntaxError("'-': weights are >= 0 (an objective is a sum of measures it minimizes)",
                                        token.col)
        return ObjectiveSyntaxError(f"expected {expected}, found {token.shown()}", token.col)

    def objective(self) -> list[tuple[str, float, int]]:
        terms = [self.term()]
        while self.take("plus"):
            terms.append(self.term())
        if self.token.kind != "end":
            raise self.fail("'+' or the end")
        return terms

    def term(self) -> tuple[str, float, int]:
        start = self.token.col
        number = self.take("number")
        if number is not None:
            if not self.take("times"):
                raise self.fail("'*' after a weight")
            name = self.take("name")
            if name is None:
                raise self.fail("a measure after '*'")
            return name.text, _number(number), start
        name = self.take("name")
        if name is None:
            raise self.fail("a measure or a number")
        if self.take("times"):
            number = self.take("number")
            if number is None:
                raise self.fail("a number after '*'")
            return name.text, _number(number), start
        return name.text, 1.0, start


def _number(token: Token) -> float:
    value = float(token.text)
    if not math.isfinite(value):
        raise ObjectiveSyntaxError(f"{token.text!r} is not a finite number", token.col)
    return value


def parse_objective(text: str) -> WeightedObjective:
    """The objective `text` spells (the module's grammar), or an ObjectiveSyntaxError saying where it does not."""
    terms = _Parser(text).objective()
    weights: dict[str, float] = {}
    for measure, weight, _ in terms:
        weights[measure] = weights.get(measure, 0.0) + weight
    if not any(w > 0 for w in weights.values()):
        raise ObjectiveSyntaxError("every weight is 0: the objective weighs no measure")
    return WeightedObjective(tuple(weights.items()))


def parse_bound(text: str) -> MeasureBound:
    """A limit `MEASURE=NUMBER` (`error=0.05`), or an ObjectiveSyntaxError saying where it is not one."""
    tokens = tokenize(text)
    expected = ("name", "equals", "number", "end")
    for k, (token, kind) in enumerate(zip(tokens, expected)):
        if token.kind == "minus" and k == 2:
            raise ObjectiveSyntaxError("'-': a bound on a measure is >= 0", token.col)
        if token.kind != kind:
            what = {"name": "a measure", "equals": "'='", "number": "a number", "end": "the end"}[kind]
            raise ObjectiveSyntaxError(f"expected {what} (MEASURE=NUMBER, e.g. error=0.05), found {token.shown()}",
                                       token.col)
    return MeasureBound(tokens[0].text, _number(tokens[2]))


def bounds_of(limits: Iterable[MeasureBound | str]) -> tuple[MeasureBound, ...]:
    """Limits (parsed or as text) checked together: a measure limited twice is an ObjectiveSyntaxError."""
    out: dict[str, MeasureBound] = {}
    for limit in limits:
        bound = parse_bound(limit) if isinstance(limit, str) else limit
        if not isinstance(bound, MeasureBound):
            raise ObjectiveSyntaxError(f"a limit is MEASURE=NUMBER text or a MeasureBound, not {type(limit).__name__}")
        if bound.measure in out:
            raise ObjectiveSyntaxError(f"{bound.measure} is limited twice ({out[bound.measure].bound:g} and "
                                       f"{bound.bound:g}): give one bound")
        out[bound.measure] = bound
    return tuple(out.values())


def objective_from_table(table: Mapping[str, object]) -> WeightedObjective:
    """The objective of a binding's `[objective]` table (measure = weight); a ValueError saying what is wrong."""
    weights = []
    for measure, weight in table.items():
        if not isinstance(measure, str) or not _NAME.match(measure):
            raise ValueError(f"{measure!r} is not a measure's name")
        if isinstance(weight, bool) or not isinstance(weight, (int, float)) or not math.isfinite(weight) \
                or weight < 0:
            raise ValueError(f"{measure} = {weight!r}: a weight is a finite number >= 0")
        weights.append((measure, float(weight)))
    if not any(w > 0 for _, w in weights):
        raise ValueError("no measure has a weight above 0 (e.g. duration = 1.0)")
    return WeightedObjective(tuple(weights))
