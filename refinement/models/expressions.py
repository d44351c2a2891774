"""Features as data (Sec. 4.1.1): small expression trees over an action's parameter names.

A generated feature is stored in its model file as JSON, never as code: a parameter name ("xg"), a finite
number (0.5), or a list [operator, argument, ...], e.g. ["hypot", ["sub", "xg", "x"], ["sub", "yg", "y"]].
Reading one checks everything (known operators and their arities, names the action has, finite constants,
bounded depth and size) before anything is computed; what fails is an ExpressionError (a ValueError) that the
model loader turns into one line naming the file. Evaluation and interval bounds live in expression_maths:
each operator has both, so a space of expressions gives the certified optimizer a guaranteed enclosure.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction

MAX_DEPTH = 12  # levels of one expression (a parameter alone is depth 1)
MAX_NODES = 96  # nodes of one expression
MAX_CONSTANT = 1e9  # |constant| in a stored expression
MAX_FEATURES = 32  # expressions of one space

# operator -> arity; what each computes is documented in expression_maths (one place for values and bounds)
ARITY: dict[str, int] = {
    "add": 2, "sub": 2, "mul": 2, "div": 2, "min": 2, "max": 2, "hypot": 2, "atan2": 2,
    "neg": 1, "abs": 1, "sqrt": 1, "square": 1, "wrap": 1, "sgn": 1, "sin": 1, "cos": 1,
    "transfer": 5,  # (displacement, start speed, goal speed, speed limit, acceleration limit): a time
    "dubins": 5,  # (goal x - start x, goal y - start y, start heading, goal heading, turning radius): a length
    "dubins_arcs": 5,  # the same arguments: the length of that shortest path's arcs (sims.dubins)
    # (start x, y, heading, goal x, y, heading, turning radius, region's xmin, xmax, ymin, ymax): the length of the
    # shortest such path that stays inside the region, and its arcs' (sims.dubins_inside)
    "dubins_inside": 11, "dubins_inside_arcs": 11,
}
# arguments that must be constants: positive ones (limits, radii), and a region's bounds (any, low below high)
CONSTANT_ARGUMENTS = {"transfer": (3, 4), "dubins": (4,), "dubins_arcs": (4,), "dubins_inside": (6, 7, 8, 9, 10),
                      "dubins_inside_arcs": (6, 7, 8, 9, 10)}
REGION_ARGUMENTS = {"dubins_inside": 7, "dubins_inside_arcs": 7}  # the first of (xmin, xmax, ymin, ymax)
INFIX = {"add": ("+", 1), "sub": ("-", 1), "mul": ("*", 2), "div": ("/", 2)}


class ExpressionError(ValueError):
    """A stored expression that is not one this module reads; the message says where and why."""


@dataclass(frozen=True)
class Expr:
    """A node: a parameter (op "param", `name`), a constant (op "const", `value`) or an operator on `args`."""

    op: str
    args: tuple[Expr, ...] = ()
    name: str = ""
    value: float = 0.0

    def __post_init__(self) -> None:
        if self.op not in ("param", "const") and len(self.args) != ARITY.get(self.op, -1):
            raise ExpressionError(f"operator {self.op!r} takes {ARITY.get(self.op, '?')} arguments, "
                                  f"got {len(self.args)}")

    @property
    def depth(self) -> int:
        return 1 + max((a.depth for a in self.args), default=0)

    @property
    def size(self) -> int:
        return 1 + sum(a.size for a in self.args)

    def parameters(self) -> set[str]:
        """The parameter names it reads."""
        if self.op == "param":
            return {self.name}
        return set().union(*(a.parameters() for a in self.args)) if self.args else set()

    def to_json(self):
        if self.op == "param":
            return self.name
        if self.op == "const":
            return self.value
        return [self.op, *(a.to_json() for a in self.args)]

    def formula(self) -> str:
        """A person's reading: infix arithmetic, |x| for abs, function calls for the rest."""
        return _text(self, 0)


def param(name: str) -> Expr:
    return Expr("param", name=name)


def const(value: float) -> Expr:
    return Expr("const", value=float(value))


def node(op: str, *args: Expr) -> Expr:
    return Expr(op, tuple(args))


def from_json(data, parameters: Sequence[str], depth: int = 1, budget: list[int] | None = None) -> Expr:
    """An expression from its JSON form, every part checked against `parameters` and the limits; an
    ExpressionError says what is wrong (checked top-down: a deep or large tree is refused before it is read
    whole, so a hostile file costs no more than MAX_NODES nodes)."""
    budget = [MAX_NODES] if budget is None else budget
    budget[0] -= 1
    if budget[0] < 0:
        raise ExpressionError(f"more than {MAX_NODES} nodes")
    if depth > MAX_DEPTH:
        raise ExpressionError(f"nested deeper than {MAX_DEPTH} levels")
    if isinstance(data, str):
        if data not in parameters:
            raise ExpressionError(f"{data[:40]!r} is not a parameter of the action ({', '.join(parameters)})")
        return param(data)
    if isinstance(data, (int, float)) and not isinstance(data, bool):
        if not math.isfinite(data) or abs(data) > MAX_CONSTANT:
            raise ExpressionError(f"constant {data!r} is not a finite number within {MAX_CONSTANT:g}")
        return const(data)
    if not isinstance(data, list) or not data or not isinstance(data[0], str):
        raise ExpressionError(f"expected a parameter name, a number or [operator, arguments...], got "
                              f"{type(data).__name__}")
    op, raw = data[0], data[1:]
    if op not in ARITY:
        raise ExpressionError(f"unknown operator {op[:40]!r} (known: {', '.join(sorted(ARITY))})")
    if len(raw) != ARITY[op]:
        raise ExpressionError(f"operator {op!r} takes {ARITY[op]} arguments, got {len(raw)}")
    args = tuple(from_json(a, parameters, depth + 1, budget) for a in raw)
    region = REGION_ARGUMENTS.get(op, -1)
    for k in CONSTANT_ARGUMENTS.get(op, ()):
        bound = 0 <= region <= k  # a region's bound: any constant
        if args[k].op != "const" or not (bound or args[k].value > 0):
            raise ExpressionError(f"argument {k + 1} of {op!r} must be a {'' if bound else 'positive '}constant")
    if region >= 0:
        xmin, xmax, ymin, ymax = (args[k].value for k in range(region, region + 4))
        if not (xmin < xmax and ymin < ymax):
            raise ExpressionError(f"the region of {op!r} must have xmin < xmax and ymin < ymax")
    return Expr(op, args)


# --- text ---------------------------------------------------------------------------------------------------
def _number(value: float) -> str:
    return format(value, ".6g")


def _text(e: Expr, context: int) -> str:
    """`e` as text; `context` is the binding strength around it (parenthesized if weaker)."""
    if e.op == "param":
        return e.name
    if e.op == "const":
        text = _number(e.value)
        return f"({text})" if e.value < 0 and context > 0 else text
    if e.op in INFIX:
        symbol, strength = INFIX[e.op]
        left = _text(e.args[0], strength)
        right = _text(e.args[1], strength + 1)  # a - (b - c), a / (b * c)
        text = f"{left} {symbol} {right}"
        return f"({text})" if strength < context else text
    if e.op == "neg":
        text = f"-{_text(e.args[0], 3)}"
        return f"({text})" if context > 0 else text
    if e.op == "abs":
        return f"|{_text(e.args[0], 0)}|"
    if e.op == "square":
        return f"{_text(e.args[0], 4)}^2"
    if e.op == "transfer":
        d, v0, vg, vmax, amax = (_text(a, 0) for a in e.args)
        return f"transfer({d}, {v0}, {vg}; vmax={vmax}, amax={amax})"
    if e.op in ("dubins", "dubins_arcs"):
        dx, dy, heading, goal_heading, radius = (_text(a, 0) for a in e.args)
        return f"{e.op}({dx}, {dy}, {heading}, {goal_heading}; r={radius})"
    if e.op in ("dubins_inside", "dubins_inside_arcs"):
        x, y, heading, xg, yg, goal_heading, radius, *region = (_text(a, 0) for a in e.args)
        return (f"{e.op}({x}, {y}, {heading}, {xg}, {yg}, {goal_heading}; r={radius}, "
                f"region=[{region[0]}, {region[1]}] x [{region[2]}, {region[3]}])")
    return f"{e.op}({', '.join(_text(a, 0) for a in e.args)})"


# --- units ----------------------------------------------------------------------------------------------
Unit = tuple[tuple[str, Fraction], ...]  # base symbol -> exponent, in order of first appearance; () = none
UNKNOWN_UNIT = "?"


def parse_unit(text: str) -> Unit:
    """'m/s^2' -> (('m', 1), ('s', -2)); '' -> (); a factor that does not parse is a symbol of its own."""
    out: dict[str, Fraction] = {}
    text = text.replace("·", "*").replace(" ", "*").strip()
    if not text:
        return ()
    parts = text.split("/")
    for k, part in enumerate(parts):
        sign = 1 if k == 0 else -1
        for factor in filter(None, part.split("*")):
            symbol, _, power = factor.partition("^")
            try:
                exponent = Fraction(power) if power else Fraction(1)
            except (ValueError, ZeroDivisionError):
                symbol, exponent = factor, Fraction(1)
            if symbol == "1":
                continue
            out[symbol] = out.get(symbol, Fraction(0)) + sign * exponent
    return tuple((s, e) for s, e in out.items() if e != 0)


def format_unit(unit: Unit | None) -> str:
    """The unit as text ('m/s^2'; '' where dimensionless; '?' where unknown)."""
    if unit is None:
        return UNKNOWN_UNIT

    def power(symbol: str, exponent: Fraction) -> str:
        value = abs(exponent)
        text = str(value.numerator) if value.denominator == 1 else format(float(value), "g")
        return symbol if value == 1 else f"{symbol}^{text}"

    top = [power(s, e) for s, e in unit if e > 0]
    bottom = [power(s, e) for s, e in unit if e < 0]
    if not bottom:
        return "*".join(top)
    return f"{'*'.join(top) or '1'}/{'*'.join(bottom)}"


def _combine(a: Unit, b: Unit, sign: int) -> Unit:
    out = dict(a)
    for s, e in b:
        out[s] = out.get(s, Fraction(0)) + sign * e
    return tuple((s, e) for s, e in out.items() if e != 0)


def _scale(a: Unit, factor: Fraction) -> Unit:
    return tuple((s, e * factor) for s, e in a)


RADIANS: Unit = (("rad", Fraction(1)),)
SECONDS: Unit = (("s", Fraction(1)),)


def unit_of(e: Expr, unit: Callable[[str], Unit]) -> Unit | None:
    """The unit of `e` given each parameter's (None where it cannot be told, e.g. metres plus seconds). A number
    fitted to the data (a distance behind a pose, a limit) has the unit its place asks for: a term scaled by one
    takes the unit of what it is added to, compared with or measured beside."""
    found = _unit_of(e, unit)
    return None if found is None else found[0]


def _unit_of(e: Expr, unit: Callable[[str], Unit]) -> tuple[Unit, bool] | None:
    """(unit, free): `free` where a number's unknown unit scales the value, so that a sum may supply one."""
    if e.op == "param":
        return unit(e.name), False
    if e.op == "const":
        return (), True
    if e.op in ("atan2", "wrap"):
        return RADIANS, False
    if e.op in ("sgn", "sin", "cos"):
        return (), False
    if e.op == "transfer":
        return SECONDS, False
    args = [_unit_of(a, unit) for a in e.args]
    if any(a is None for a in args):
        return None
    if e.op in ("add", "sub", "min", "max", "hypot", "dubins", "dubins_arcs", "dubins_inside", "dubins_inside_arcs"):
        # (a path: of its first two arguments, the positions' or their differences')
        (a, free_a), (b, free_b) = args[0], args[1]
        if dict(a) == dict(b):
            return a, free_a and free_b
        if free_a or free_b:
            return (b, False) if free_a and not free_b else (a, False) if free_b and not free_a else None
        return None
    if e.op in ("neg", "abs"):
        return args[0]
    if e.op == "mul":
        return _combine(args[0][0], args[1][0], 1), args[0][1] or args[1][1]
    if e.op == "div":
        return _combine(args[0][0], args[1][0], -1), args[0][1] or args[1][1]
    if e.op == "sqrt":
        return _scale(args[0][0], Fraction(1, 2)), args[0][1]
    if e.op == "square":
        return _scale(args[0][0], Fraction(2)), args[0][1]
    return None


def units_of(parameter_units: Mapping[str, str]) -> Callable[[str], Unit]:
    """A parameter -> Unit lookup from declared unit texts (a parameter not declared has none)."""
    parsed = {name: parse_unit(text) for name, text in parameter_units.items()}
    return lambda name: parsed.get(name, ())
