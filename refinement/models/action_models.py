"""Learned action models (Chapter 4) as frozen values with a JSON form, and their loaders.

An ActionModel predicts how long an action takes from its parameters (observed, then internal): the
parameters are mapped to a feature space (Table 4.1) and a model tree predicts the duration there. Where the
binding's recipe declares more measures (`measures = ["duration", "energy", "error"]`, Ch. 8.1), the same file
holds a MeasureModel per further measure: a model tree over the same features, trained by the same protocol.
One file per action, whatever it measures: `<action>.json` of schema `tailor.action_model/2` with a `measures`
object (measure -> tree, report, uncertainty, unit); a file without one is written as `tailor.action_model/1`,
as before, and both are read.
A CollisionModel (a success classifier) predicts whether an action reaches its goal without failing, e.g.
without bumping an object lying there (Sec. 4.2.2).
Files are JSON with a schema key, never pickle: loading a model must not run code.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tailor.refinement.models.decision_tree import DecisionTree, LeafBox, check_failures
from tailor.errors import ModelFileError, check_path_argument, is_finite
from tailor.refinement.models.expression_space import AUTO, ExpressionSpace
from tailor.refinement.models.expressions import ExpressionError
from tailor.refinement.models.features import compute_features, feature_space as registered_space, feature_spaces
from tailor.sims.protocol import FeatureSpace
from tailor.refinement.models.model_tree import ModelTree
from tailor.refinement.models.rules import Rule
from tailor.refinement.models.uncertainty import LeafUncertainty, risk_adjusted

ACTION_MODEL_SCHEMA = "tailor.action_model/1"  # the duration model alone (what every file held before measures)
MEASURES_SCHEMA = "tailor.action_model/2"  # 2: also models of further measures (`measures`), same features
ACTION_MODEL_SCHEMAS = (ACTION_MODEL_SCHEMA, MEASURES_SCHEMA)
DURATION = "duration"  # the measure the `duration` tree predicts (objective_grammar.DURATION)
COLLISION_MODEL_SCHEMA = "tailor.collision_model/1"
COLLISION_SUFFIX = ".collision.json"  # <action>.collision.json: the action's success classifier
# In a leaf's failure probability, the Laplace estimate from its training episodes weighs as this many of the
# classifier's fresh episodes there (report.fresh_leaves). Chosen on 20000 held-out episodes of a bundled classifier
# (issue 35): in the leaves predicting failure where most training episodes succeeded, log-loss 0.419 with 2 or 5
# (1: 0.422, 10: 0.422, 40: 0.429; the training estimate alone 0.435); 5 is the better of the two over all leaves.
FRESH_PRIOR = 5.0
META_FILE = "meta.json"  # the meta action model (tailor.refinement.models.meta_model), not an action's
# A predicted duration is plausible within the durations seen in training, [lo, hi] (report.duration_range;
# for files without it [0, OLD_FILE_SPAN * mean_duration]), widened by RANGE_MARGIN times its width on each
# side. Outside (or not finite) the model file is broken: ModelFileError. A plausible prediction below zero
# (a linear leaf extrapolating a little) is clipped to 0 s: no action takes negative time.
RANGE_MARGIN = 1.0
OLD_FILE_SPAN = 2.0
NO_REPORT_BOUND = 86400.0  # s: plausible for a file that states neither (one day either side)
FEATURE_SPACE_KEY = "feature_space"  # a model file's feature space (Table 4.1), as the binding names it
EXPRESSIONS_KEY = "expressions"  # a generated space's features as expression trees (models.expression_space)
OLD_FEATURE_SPACE_KEY = "feature_set"  # the same in files written before: still read, never written
_MEASURE_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


@dataclass(frozen=True, eq=False)
class ActionModel:
    """Predicts an action's execution duration (s) from its parameters with a model tree over features."""

    action: str
    feature_space: str
    feature_names: tuple[str, ...]
    duration: ModelTree
    n_i: int  # intermediate examples per episode it was trained with (Sec. 4.1.2)
    report: dict = field(default_factory=dict)
    source: str | None = field(default=None, compare=False)  # the file it was read from, for error messages
    # per-leaf held-out spread (models.uncertainty); None in files trained before it existed
    uncertainty: LeafUncertainty | None = None
    # the features as expressions where they were generated (feature_space "auto"); None: a registered space
    expressions: ExpressionSpace | None = None
    # models of further measures over the same features (Ch. 8.1), by measure; empty: the duration alone
    measures: Mapping[str, MeasureModel] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.expressions is not None and tuple(self.feature_names) != self.expressions.names:
            raise ValueError(f"feature names {self.feature_names} are not its expressions' {self.expressions.names}")
        if DURATION in self.measures:
            raise ValueError("the duration is the model's own tree, not one of its measures")
        object.__setattr__(self, "measures", dict(self.measures))  # (a copy; a dict pickles to worker processes)

    @property
    def measure_names(self) -> tuple[str, ...]:
        """Every measure it predicts: the duration, then its further measures."""
        return (DURATION, *self.measures)

    def measure(self, name: str) -> MeasureModel:
        """The model of a further measure; a ModelFileError naming the file where it has none."""
        try:
            return self.measures[name]
        except KeyError:
            raise ModelFileError(f"the action model of {self.action} has no model of {name!r} (it predicts "
                                 f"{', '.join(self.measure_names)}): declare it in the binding's "
                                 f"[training.models.{self.action}] measures and retrain with `tailor train`",
                                 file=self.source) from None

    def tree_of(self, name: str):
        """The model tree predicting measure `name` (the duration's own, or a further measure's)."""
        return self.duration if name == DURATION else self.measure(name).tree

    def measure_with_risk(self, name: str, risk: float):
        """What a risk-aware objective sums for measure `name`: its tree at risk 0, else its prediction plus risk
        times its own leaves' held-out spread (a ModelFileError where that measure stores none)."""
        if name == DURATION:
            return self.duration_with_risk(risk)
        model = self.measure(name)
        if risk == 0:
            return model.tree
        if model.uncertainty is None:
            raise ModelFileError(f"the {name} model of {self.action} has no uncertainty: refine with --risk 0",
                                 file=self.source)
        return risk_adjusted(model.tree, model.uncertainty, risk)

    def predict_measure(self, name: str, params: np.ndarray) -> np.ndarray:
        """Predicted measure `name` (its unit) for each row of (n, p) action parameters."""
        if name == DURATION:
            return self.predict_duration(params)
        with np.errstate(over="ignore", invalid="ignore"):
            return np.asarray(self.measure(name).tree.predict(self.features(params)), dtype=float)

    def check_measure(self, name: str, value: float, where: str) -> float:
        """`value` checked as check_duration checks a duration: clipped at 0 if plausible for the measure's
        model, else a ModelFileError naming the file."""
        if name == DURATION:
            return self.check_duration(value, where)
        return self.measure(name).check(value, where, self.source)

    @property
    def space(self) -> FeatureSpace:
        """Its feature space as a FeatureSpace: the generated one (with `bounds`, a guaranteed enclosure of the
        features over boxes of parameters, for the certified optimizer) or the registered one it names."""
        if self.expressions is not None:
            cached = self.__dict__.get("_space")
            if cached is None:
                cached = self.expressions.feature_space(self.feature_space)
                object.__setattr__(self, "_space", cached)
            return cached
        return registered_space(self.feature_space)

    def features(self, params: np.ndarray) -> np.ndarray:
        """(n, p) action parameters -> (n, f) features; parameters of another shape than the space reads are a
        ModelFileError naming the file (a model of another action's parameters)."""
        try:
            if self.expressions is not None:
                return self.space(params)
            return compute_features(self.feature_space, params)
        except ValueError as exc:
            raise ModelFileError(str(exc), file=self.source) from None

    def predict_duration(self, params: np.ndarray) -> np.ndarray:
        """Predicted duration (s) for each row of (n, p) action parameters."""
        with np.errstate(over="ignore", invalid="ignore"):  # absurd coefficients: see check_duration
            return np.asarray(self.duration.predict(self.features(params)), dtype=float)

    def predict_spread(self, params: np.ndarray) -> np.ndarray:
        """How far off (s, held-out mean absolute error of the leaf) each row's predicted duration tends to be."""
        return self.require_uncertainty().of_leaves(self.duration.apply(self.features(params)))

    def duration_with_risk(self, risk: float):
        """What a risk-aware objective sums for this action: the duration tree itself at risk 0, else a tree
        predicting duration + risk * spread (the same leaves, each with a larger intercept)."""
        if risk == 0:
            return self.duration
        return risk_adjusted(self.duration, self.require_uncertainty(), risk)

    def require_uncertainty(self) -> LeafUncertainty:
        """The model's uncertainty, or a ModelFileError naming its file where it was trained without one."""
        if self.uncertainty is None:
            raise ModelFileError(f"the action model of {self.action} has no uncertainty (trained before it was "
                                 "stored): retrain with `tailor train`, or refine with --risk 0", file=self.source)
        return self.uncertainty

    def plausible_range(self) -> tuple[float, float]:
        """The durations a prediction may take (see RANGE_MARGIN; within a day either side where the report
        says nothing of them)."""
        seen = self.report.get("duration_range")
        mean = self.report.get("mean_duration")
        if (isinstance(seen, list) and len(seen) == 2 and all(_is_number(v) for v in seen)
                and seen[0] <= seen[1]):
            lo, hi = float(seen[0]), float(seen[1])
        elif _is_number(mean) and mean > 0:
            lo, hi = 0.0, OLD_FILE_SPAN * float(mean)
        else:  # a file that says nothing of its durations: no action of any robot here takes days
            return -NO_REPORT_BOUND, NO_REPORT_BOUND
        margin = RANGE_MARGIN * (hi - lo)
        return lo - margin, hi + margin

    def check_duration(self, value: float, where: str) -> float:
        """`value` clipped at 0 s if it is a plausible prediction of this model, else a ModelFileError naming its
        file: an absurd model (huge or infinite coefficients, a shifted intercept) must not be refined with."""
        bounds = self.plausible_range()
        if not math.isfinite(value):
            raise ModelFileError(f"{where}: the model predicts a duration of {value} s: its coefficients are "
                                 "broken (retrain with `tailor train`)", file=self.source)
        if not bounds[0] <= value <= bounds[1]:
            raise ModelFileError(f"{where}: the model predicts {value:.4g} s, outside the plausible "
                                 f"[{bounds[0]:.3g}, {bounds[1]:.3g}] s (the durations seen in training, with a "
                                 "margin): the file is inconsistent (retrain with `tailor train`)", file=self.source)
        return max(0.0, value)

    def rules_text(self) -> str:
        return self.duration.export_text(list(self.feature_names))

    def to_json(self) -> dict:
        """Schema 1 for the duration alone (the same bytes as before measures existed), 2 with measures."""
        return {
            "schema": MEASURES_SCHEMA if self.measures else ACTION_MODEL_SCHEMA,
            "action": self.action,
            FEATURE_SPACE_KEY: self.feature_space,
            "feature_names": list(self.feature_names),
            **({} if self.expressions is None else {EXPRESSIONS_KEY: self.expressions.to_json()}),
            "n_i": self.n_i,
            "rules": self.rules_text().splitlines(),
            "duration": self.duration.to_json(),
            "report": self.report,
            **({} if self.uncertainty is None else {"uncertainty": self.uncertainty.to_json()}),
            **({} if not self.measures else
               {"measures": {name: m.to_json(self.feature_names) for name, m in self.measures.items()}}),
        }

    @classmethod
    def from_json(cls, data: dict, source: str) -> ActionModel:
        """Build from parsed JSON; anything malformed raises ModelFileError naming `source`."""
        _check_schema(data, ACTION_MODEL_SCHEMAS, source)
        expressions = _expressions(data, source)
        action, space, names = _common_fields(data, source, expressions)
        n_i = data.get("n_i")
        if not isinstance(n_i, int) or isinstance(n_i, bool) or n_i < 1:
            raise ModelFileError(f"'n_i' must be a positive integer, got {n_i!r}", file=source)
        tree = _model_tree(data.get("duration"), "'duration'", "duration", len(names), source)
        uncertainty = None
        if "uncertainty" in data:  # optional: files written before it existed load without it
            uncertainty = LeafUncertainty.from_json(data["uncertainty"], tree.n_leaves_, source)
        measures = _measures(data, source, len(names))
        return cls(action, space, names, tree, n_i, _report(data, source), source, uncertainty, expressions, measures)


@dataclass(frozen=True, eq=False)
class MeasureModel:
    """Predicts one more measure of an action (Ch. 8.1: energy in J, end error in m, ...) from the features of
    its action model, with a model tree trained by the duration's protocol on the first example of each
    episode (an episode's log does not say how much of a measure was spent by a later row)."""

    measure: str
    unit: str
    tree: ModelTree
    n_i: int
    report: dict = field(default_factory=dict)
    uncertainty: LeafUncertainty | None = None

    def plausible_range(self) -> tuple[float, float]:
        """The values a prediction may take: those seen in training (report `range`), widened by RANGE_MARGIN
        times their width on each side (as a duration's)."""
        seen = self.report.get("range")
        if not (isinstance(seen, list) and len(seen) == 2 and all(_is_number(v) for v in seen) and seen[0] <= seen[1]):
            return -NO_REPORT_BOUND, NO_REPORT_BOUND
        margin = RANGE_MARGIN * (seen[1] - seen[0])
        return seen[0] - margin, seen[1] + margin

    def check(self, value: float, where: str, source: str | None) -> float:
        """`value` clipped at 0 (a measure here is an energy or a distance) if plausible, else a ModelFileError."""
        unit = f" {self.unit}" if self.unit else ""
        if not math.isfinite(value):
            raise ModelFileError(f"{where}: the {self.measure} model predicts {value}{unit}: its coefficients are "
                                 "broken (retrain with `tailor train`)", file=source)
        low, high = self.plausible_range()
        if not low <= value <= high:
            raise ModelFileError(f"{where}: the {self.measure} model predicts {value:.4g}{unit}, outside the "
                                 f"plausible [{low:.3g}, {high:.3g}]{unit} (the values seen in training, with a "
                                 "margin): the file is inconsistent (retrain with `tailor train`)", file=source)
        return max(0.0, value)

    def rules_text(self, feature_names) -> str:
        return self.tree.export_text(list(feature_names))

    def to_json(self, feature_names) -> dict:
        return {"unit": self.unit, "n_i": self.n_i, "rules": self.rules_text(feature_names).splitlines(),
                "tree": self.tree.to_json(), "report": self.report,
                **({} if self.uncertainty is None else {"uncertainty": self.uncertainty.to_json()})}

    @classmethod
    def from_json(cls, measure: str, data, source: str, n_features: int) -> MeasureModel:
        """Check and rebuild the model of `measure`; any problem is a ModelFileError naming `source`."""
        where = f"measures.{measure}"
        if not isinstance(data, dict):
            raise ModelFileError(f"'{where}' must be an object", file=source)
        unit, n_i = data.get("unit", ""), data.get("n_i")
        if not isinstance(unit, str):
            raise ModelFileError(f"'{where}.unit' must be a string", file=source)
        if not isinstance(n_i, int) or isinstance(n_i, bool) or n_i < 1:
            raise ModelFileError(f"'{where}.n_i' must be a positive integer, got {n_i!r}", file=source)
        tree = _model_tree(data.get("tree"), f"'{where}.tree'", measure, n_features, source)
        report = data.get("report", {})
        if not isinstance(report, dict):
            raise ModelFileError(f"'{where}.report' must be an object", file=source)
        seen = report.get("range")
        if seen is not None and not (isinstance(seen, list) and len(seen) == 2 and all(_is_number(v) for v in seen)
                                     and seen[0] <= seen[1]):
            raise ModelFileError(f"'{where}.report.range' must be [least, most] seen in training, got {seen!r}",
                                 file=source)
        uncertainty = None
        if "uncertainty" in data:
            uncertainty = LeafUncertainty.from_json(data["uncertainty"], tree.n_leaves_, source)
        return cls(measure, unit, tree, n_i, report, uncertainty)


def _measures(data: dict, source: str, n_features: int) -> dict[str, MeasureModel]:
    """The further measures' models of a schema-2 file (none in a schema-1 file, which may not name any)."""
    if "measures" not in data:
        return {}
    if data.get("schema") != MEASURES_SCHEMA:
        raise ModelFileError(f"'measures' needs schema {MEASURES_SCHEMA!r}", file=source)
    measures = data["measures"]
    if not isinstance(measures, dict) or not measures:
        raise ModelFileError("'measures' must be an object of measure -> model", file=source)
    out = {}
    for name, model in measures.items():
        if not isinstance(name, str) or not _MEASURE_NAME.match(name) or name == DURATION:
            raise ModelFileError(f"'measures' names {name!r}, not a further measure", file=source)
        out[name] = MeasureModel.from_json(name, model, source, n_features)
    return out


@dataclass(frozen=True, eq=False)
class CollisionModel:
    """Predicts whether an action reaches its goal without failing, e.g. without bumping an object at its goal (Sec. 4.2.2).

    The decision tree was trained with a cost matrix that makes it pessimistic: where in doubt it predicts
    a collision, since a wrongly predicted success costs more (an asserted subgoal only costs some time).
    """

    action: str
    feature_space: str
    feature_names: tuple[str, ...]
    tree: DecisionTree
    report: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        inner = self.tree.children_left != -1
        if np.any((self.tree.feature[inner] < 0) | (self.tree.feature[inner] >= len(self.feature_names))):
            raise ValueError(f"a node tests a feature outside 0..{len(self.feature_names) - 1}")

    def features(self, params: np.ndarray) -> np.ndarray:
        return compute_features(self.feature_space, params)

    def predict_success(self, params: np.ndarray) -> np.ndarray:
        """True where the action is predicted to reach its goal without failing, per row of (n, p)."""
        return self.tree.predict(self.features(params))

    def leaf(self, params: np.ndarray) -> np.ndarray:
        """The tree node (leaf) each row of (n, p) parameters reaches: where a prediction comes from."""
        return self.tree.apply(self.features(params))

    def failure_probability(self, params: np.ndarray) -> tuple[np.ndarray, tuple[str, ...]] | None:
        """Per row of (n, p) parameters, the probability of failing from the leaf it reaches, and where that comes
        from (the leaf and its counts): (failed + 1) / (samples + 2) of the training episodes there (Laplace), and
        where the report counts the fresh episodes into the leaves (`fresh_leaves`), their failures with that
        estimate as a prior worth FRESH_PRIOR of them. The training episodes chose the splits, so a small leaf cut
        around a chance cluster of failures overstates them (one of 11 in 40 failed in 5 of 87 held-out episodes);
        the fresh ones chose nothing. None for a tree without the counts (a file written before they were kept)."""
        leaves = self.leaf(params)
        probability = self.tree.failure_probability(leaves)
        if probability is None:
            return None
        sources = [f"leaf {leaf} of {self.action}'s classifier ({self.tree.failures[leaf]} of its "
                   f"{self.tree.samples[leaf]} training episodes failed, Laplace" for leaf in leaves]
        fresh = self.report.get("fresh_leaves")
        if fresh is None:
            return probability, tuple(f"{s})" for s in sources)
        n, failed = (np.asarray(fresh[key], dtype=np.int64)[leaves] for key in ("samples", "failures"))
        probability = (failed + FRESH_PRIOR * probability) / (n + FRESH_PRIOR)
        return probability, tuple(f"{s}; {f} of its {k} fresh episodes)" for s, f, k in zip(sources, failed, n))

    def success_rules(self) -> list[Rule]:
        """The leaves predicting success as rules with a zero linear model: intersected with a model tree's
        rules (App. C.3.3) they restrict the analytic minimization to the predicted-success region (Alg. 6)."""
        n = len(self.feature_names)
        return [Rule(box.lower, box.upper, np.zeros(n), 0.0) for box in self.tree.success_boxes(n)]

    def regions(self) -> list[LeafBox]:
        """The tree's leaves as boxes in feature space (lower < x <= upper), each predicting success or not."""
        return self.tree.leaf_boxes(len(self.feature_names))

    def rules_text(self) -> str:
        return self.tree.export_text(self.feature_names)

    def to_json(self) -> dict:
        return {
            "schema": COLLISION_MODEL_SCHEMA,
            "action": self.action,
            FEATURE_SPACE_KEY: self.feature_space,
            "feature_names": list(self.feature_names),
            "rules": self.rules_text().splitlines(),
            "tree": self.tree.to_json(),
            "report": self.report,
        }

    @classmethod
    def from_json(cls, data: dict, source: str) -> CollisionModel:
        _check_schema(data, COLLISION_MODEL_SCHEMA, source)
        action, space, names = _common_fields(data, source)
        try:
            tree = DecisionTree.from_json(data["tree"])
            report = _report(data, source)
            _check_fresh_leaves(report, tree)
            return cls(action, space, names, tree, report)
        except (KeyError, TypeError, ValueError, OverflowError) as exc:
            raise ModelFileError(f"invalid decision tree: {exc}", file=source) from None


def load_action_models(models_dir: Path, actions: tuple[str, ...] | None = None) -> dict[str, ActionModel]:
    """Every duration model `<action>.json` in `models_dir`, keyed by action (`actions` must all be present)."""
    check_path_argument(models_dir, "models_dir")
    models_dir = Path(models_dir)
    if not models_dir.is_dir():
        raise ModelFileError("model directory not found", file=str(models_dir))
    if actions is not None:
        paths = [models_dir / f"{action}.json" for action in actions]
    else:
        paths = sorted(p for p in models_dir.glob("*.json")
                       if not p.name.endswith(COLLISION_SUFFIX) and p.name != META_FILE)
        if not paths:
            raise ModelFileError("no action model files (<action>.json)", file=str(models_dir))
    models = {}
    for path in paths:
        model = ActionModel.from_json(read_json(path), str(path))
        if model.action != path.name.removesuffix(".json"):
            raise ModelFileError(f"holds the model of {model.action!r}, not of its file name's action", file=str(path))
        models[model.action] = model
    return models


def load_collision_model(path: Path) -> CollisionModel:
    """A success classifier, `<models_dir>/<action>.collision.json`."""
    return CollisionModel.from_json(read_json(Path(path)), str(path))


def load_success_models(models_dir: Path, names) -> dict[str, CollisionModel]:
    """The success classifiers `<name>.collision.json` in `models_dir` for each of `names`, keyed by name."""
    models = {}
    for name in sorted(set(names)):
        path = Path(models_dir) / f"{name}{COLLISION_SUFFIX}"
        if not path.is_file():
            raise ModelFileError(f"no success classifier {path.name} for subgoal assertion (train it with "
                                 "`tailor train`: [training.classifiers])", file=str(path))
        models[name] = load_collision_model(path)
    return models


def read_json(path: Path) -> dict:
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ModelFileError("file not found", file=str(path)) from None
    except OSError as exc:
        raise ModelFileError(f"cannot read: {exc.strerror}", file=str(path)) from None
    except UnicodeDecodeError as exc:
        raise ModelFileError(f"not JSON: not UTF-8 text (byte {exc.start})", file=str(path)) from None
    try:
        data = json.loads(text, parse_constant=_reject_constant,
                          parse_int=lambda digits: int(digits) if len(digits) <= 20 else float(digits))
    except json.JSONDecodeError as exc:
        raise ModelFileError(f"not JSON: {exc.msg}", file=str(path), line=exc.lineno, col=exc.colno) from None
    except ValueError as exc:  # NaN / Infinity, which JSON does not have; or numbers too deeply nested
        raise ModelFileError(f"not JSON: {exc}", file=str(path)) from None
    except RecursionError:
        raise ModelFileError("not JSON: nested too deeply", file=str(path)) from None
    if not isinstance(data, dict):
        raise ModelFileError("expected a JSON object", file=str(path))
    return data


def _reject_constant(name: str):
    raise ValueError(f"{name} is not a JSON number (models hold finite numbers only)")


def write_json_atomic(path: Path, data: dict) -> None:
    """Write JSON to a temp file beside `path`, then rename it over `path`: never a half-written file; the
    file gets the permissions of any new file (0666 less the umask)."""
    from tailor.outputs import write_atomically

    write_atomically(path, lambda tmp: tmp.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8"))


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and is_finite(value)


def _check_schema(data: dict, schema: str | tuple[str, ...], source: str) -> None:
    schemas = (schema,) if isinstance(schema, str) else schema
    if data.get("schema") not in schemas:
        raise ModelFileError(f"schema is {data.get('schema')!r}, expected "
                             + " or ".join(repr(s) for s in schemas), file=source)


def _expressions(data: dict, source: str) -> ExpressionSpace | None:
    """The generated features a model file stores (None where it names a registered space); anything malformed
    or hostile is one ModelFileError naming the file, before anything is computed."""
    if EXPRESSIONS_KEY not in data:
        return None
    try:
        return ExpressionSpace.from_json(data[EXPRESSIONS_KEY])
    except ExpressionError as exc:
        raise ModelFileError(f"'{EXPRESSIONS_KEY}': {exc}", file=source) from None


def _common_fields(data: dict, source: str, expressions: ExpressionSpace | None = None
                   ) -> tuple[str, str, tuple[str, ...]]:
    """(action, feature space, feature names) of a model file; the space under FEATURE_SPACE_KEY, or under the
    older key `feature_set` in files written before it was named so (the bundled models among them); a file
    with expressions names its space "auto" and its features are the expressions' names."""
    action, names = data.get("action"), data.get("feature_names")
    space = data.get(FEATURE_SPACE_KEY, data.get(OLD_FEATURE_SPACE_KEY))
    if not isinstance(action, str) or not action:
        raise ModelFileError("'action' must be a non-empty string", file=source)
    if expressions is not None or space == AUTO:
        if expressions is None:
            raise ModelFileError(f"feature space {AUTO!r} without its '{EXPRESSIONS_KEY}'", file=source)
        if space != AUTO:
            raise ModelFileError(f"a file with '{EXPRESSIONS_KEY}' names its feature space {AUTO!r}, not {space!r}",
                                 file=source)
        if not isinstance(names, list) or tuple(names) != expressions.names:
            raise ModelFileError(f"feature_names {names!r} do not match its expressions {list(expressions.names)}",
                                 file=source)
        return action, space, expressions.names
    spaces = feature_spaces()
    if not isinstance(space, str) or space not in spaces:
        raise ModelFileError(f"unknown feature space {space!r} (known: {', '.join(sorted(spaces))})", file=source)
    expected = spaces[space].names
    if not isinstance(names, list) or tuple(names) != expected:
        raise ModelFileError(f"feature_names {names!r} do not match feature space {space!r} {list(expected)}",
                             file=source)
    return action, space, expected


def _report(data: dict, source: str) -> dict:
    report = data.get("report", {})
    if not isinstance(report, dict):
        raise ModelFileError("'report' must be an object", file=source)
    seen = report.get("duration_range")
    if seen is not None and not (isinstance(seen, list) and len(seen) == 2 and all(_is_number(v) for v in seen)
                                 and math.isfinite(seen[0]) and math.isfinite(seen[1]) and 0 <= seen[0] <= seen[1]):
        raise ModelFileError(f"'report.duration_range' must be [shortest, longest] seconds seen in training, "
                             f"got {seen!r}", file=source)
    return report


def _check_fresh_leaves(report: dict, tree: DecisionTree) -> None:
    """ValueError unless the report's `fresh_leaves` (if any) counts episodes and failures, one of each per node."""
    fresh = report.get("fresh_leaves")
    if fresh is None:
        return
    counts = (fresh.get("samples"), fresh.get("failures")) if isinstance(fresh, dict) else (None, None)
    if not all(isinstance(c, list) and all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in c)
               for c in counts) or len(counts[0]) != len(tree.children_left):
        raise ValueError(f"report.fresh_leaves must hold samples and failures, {len(tree.children_left)} "
                         "counts each (one per node)")
    check_failures(np.asarray(counts[1], dtype=np.int64), np.asarray(counts[0], dtype=np.int64))


def _model_tree(data, where: str, measure: str, n_features: int, source) -> ModelTree:
    """A measure's model tree read from its JSON object `data` (at `where` in the file), checked to take the
    feature space's `n_features` features: anything else is a ModelFileError naming the file."""
    if not isinstance(data, dict):
        raise ModelFileError(f"{where} must be a model tree object", file=source)
    try:
        tree = ModelTree.from_json(data, source)
    except ModelFileError:
        raise
    except (KeyError, TypeError, ValueError, OverflowError) as exc:
        raise ModelFileError(f"invalid {measure} model tree: {exc}", file=source) from None
    n_in = getattr(tree, "n_features_in_", None)
    if n_in != n_features:
        raise ModelFileError(f"{measure} model tree takes {n_in} features, feature space has {n_features}",
                             file=source)
    return tree
