"""A feature space of expressions (Sec. 4.1.1): named expression trees over an action's parameters, compiled
once into a flat program (each distinct subexpression computed once per call), evaluated with numpy and bounded
by interval arithmetic. Its `feature_space()` is a FeatureSpace like the registered ones, with `bounds`: the
certified optimizer asks any model for its space and gets a guaranteed enclosure of these features."""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from tailor.refinement.models.expression_maths import evaluate, interval
from tailor.refinement.models.expressions import (CONSTANT_ARGUMENTS, MAX_FEATURES, Expr, ExpressionError,
                                                  format_unit, from_json, unit_of, units_of)
from tailor.sims.protocol import FeatureSpace

AUTO = "auto"  # the binding's and the model file's name of a generated feature space
NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.]{0,63}$")
INVARIANCE = "what its expressions do not read (differences, distances and relative angles of like quantities)"


@dataclass(frozen=True, eq=False)
class ExpressionSpace:
    """Features `names` = `expressions` over the action's `parameters` (in the action's order); `units` the
    feature units as text, for people (the model file keeps them beside each formula)."""

    parameters: tuple[str, ...]
    names: tuple[str, ...]
    expressions: tuple[Expr, ...]
    units: tuple[str, ...] = ()
    _program: list = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.expressions or len(self.expressions) > MAX_FEATURES:
            raise ExpressionError(f"a space holds 1 to {MAX_FEATURES} features, got {len(self.expressions)}")
        if len(self.names) != len(self.expressions) or len(set(self.names)) != len(self.names):
            raise ExpressionError("feature names must be distinct, one per expression")
        for name in self.names:
            if not isinstance(name, str) or not NAME.match(name):
                raise ExpressionError(f"feature name {str(name)[:40]!r} is not a name (A-Z, a-z, 0-9, _ and .)")
        unknown = set().union(*(e.parameters() for e in self.expressions)) - set(self.parameters)
        if unknown:
            raise ExpressionError(f"reads {', '.join(sorted(unknown))}, not parameters of the action")
        if self.units and len(self.units) != len(self.names):
            raise ExpressionError("one unit per feature")
        object.__setattr__(self, "_program", _compile(self.expressions, self.parameters))

    @property
    def formulas(self) -> tuple[str, ...]:
        return tuple(e.formula() for e in self.expressions)

    def compute(self, params: np.ndarray) -> np.ndarray:
        """(n, len(parameters)) -> (n, len(names))."""
        params = np.asarray(params, dtype=float)
        columns = [params[:, k] for k in range(params.shape[1])]
        values = _run(self._program, columns, evaluate, pairs=False)
        return np.column_stack(values) if values else np.empty((len(params), 0))

    def bounds(self, low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A guaranteed enclosure of the features over k boxes of parameters: (low, high) each (k, len(parameters))
        -> (feature_low, feature_high) each (k, len(names)), by interval arithmetic through every operator."""
        low, high = np.atleast_2d(np.asarray(low, dtype=float)), np.atleast_2d(np.asarray(high, dtype=float))
        if low.shape != high.shape or low.shape[1] != len(self.parameters):
            raise ValueError(f"bounds take (k, {len(self.parameters)}) arrays, got {low.shape} and {high.shape}")
        columns = [(low[:, k], high[:, k]) for k in range(low.shape[1])]
        pairs = _run(self._program, columns, interval, pairs=True)
        return np.column_stack([p[0] for p in pairs]), np.column_stack([p[1] for p in pairs])

    def feature_space(self, name: str = AUTO, invariance: str = INVARIANCE) -> FeatureSpace:
        """This space as a FeatureSpace (with its bounds), for everything that takes one."""
        return FeatureSpace(name, self.parameters, self.names, self.compute, invariance, None, self.bounds)

    def with_units(self, parameter_units: Mapping[str, str]) -> ExpressionSpace:
        """The same space with each feature's unit worked out from the parameters' declared units."""
        unit = units_of(parameter_units)
        units = tuple(format_unit(unit_of(e, unit)) for e in self.expressions)
        return ExpressionSpace(self.parameters, self.names, self.expressions, units)

    def describe(self) -> list[dict]:
        """Per feature: name, formula and unit (what reports print)."""
        units = self.units or ("",) * len(self.names)
        return [{"name": n, "formula": f, "unit": u} for n, f, u in zip(self.names, self.formulas, units)]

    def to_json(self) -> dict:
        units = self.units or ("",) * len(self.names)
        return {"parameters": list(self.parameters),
                "features": [{"name": n, "expression": e.to_json(), "formula": e.formula(), "unit": u}
                             for n, e, u in zip(self.names, self.expressions, units)]}

    @classmethod
    def from_json(cls, data, parameters: Sequence[str] | None = None) -> ExpressionSpace:
        """Read and check a stored space (ExpressionError saying where); `parameters`, where given, must be the
        ones it declares (the action's)."""
        if not isinstance(data, dict):
            raise ExpressionError("'expressions' must be an object with 'parameters' and 'features'")
        declared = data.get("parameters")
        if (not isinstance(declared, list) or not declared or len(declared) > 64
                or not all(isinstance(p, str) and NAME.match(p) for p in declared)):
            raise ExpressionError("'parameters' must be a list of the action's parameter names")
        if parameters is not None and tuple(declared) != tuple(parameters):
            raise ExpressionError(f"its parameters {declared} are not the action's {list(parameters)}")
        features = data.get("features")
        if not isinstance(features, list) or not 0 < len(features) <= MAX_FEATURES:
            raise ExpressionError(f"'features' must be a list of 1 to {MAX_FEATURES} features")
        names, expressions, units = [], [], []
        for k, feature in enumerate(features):
            if not isinstance(feature, dict) or not isinstance(feature.get("name"), str):
                raise ExpressionError(f"features[{k}] must be an object with a 'name' and an 'expression'")
            try:
                expressions.append(from_json(feature.get("expression"), tuple(declared)))
            except ExpressionError as exc:
                raise ExpressionError(f"features[{k}] ({feature['name'][:40]!r}): {exc}") from None
            unit = feature.get("unit", "")
            names.append(feature["name"])
            units.append(unit if isinstance(unit, str) and len(unit) <= 40 else "")
        return cls(tuple(declared), tuple(names), tuple(expressions), tuple(units))


def _compile(expressions: Sequence[Expr], parameters: Sequence[str]) -> list:
    """A flat program: (op, argument slots, constants, parameter column) per distinct node, children first; the
    last len(expressions) entries of `outputs` name the slots of the features."""
    slots: dict[Expr, int] = {}
    steps: list[tuple] = []
    index = {name: k for k, name in enumerate(parameters)}

    def visit(e: Expr) -> int:
        if e in slots:
            return slots[e]
        if e.op == "param":
            step = ("param", (), (), index[e.name])
        elif e.op == "const":
            step = ("const", (), (e.value,), -1)
        else:
            fixed = CONSTANT_ARGUMENTS.get(e.op, ())
            args = tuple(visit(a) for k, a in enumerate(e.args) if k not in fixed)
            step = (e.op, args, tuple(e.args[k].value for k in fixed), -1)
        steps.append(step)
        slots[e] = len(steps) - 1
        return slots[e]

    outputs = [visit(e) for e in expressions]
    return [steps, outputs]


def _run(program: list, columns: list, apply: Callable, pairs: bool) -> list:
    """Run the program on parameter columns (arrays, or (low, high) pairs of arrays where `pairs`);
    `apply(op, args, constants)` computes one step."""
    steps, outputs = program
    shape = np.shape(columns[0][0] if pairs else columns[0])
    values: list = []
    for op, args, constants, column in steps:
        if op == "param":
            values.append(columns[column])
        elif op == "const":
            value = np.full(shape, constants[0])
            values.append((value, value) if pairs else value)
        else:
            values.append(apply(op, [values[a] for a in args], constants))
    return [values[k] for k in outputs]
