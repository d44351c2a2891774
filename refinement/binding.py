"""The action library binding (Sec. 5.3): a declarative TOML file per domain, `domains/<name>/actions.toml`.

It names the simulator whose executable actions the domain uses (a name in the simulator registry), says
which executable action each PDDL action maps to and which PDDL argument supplies each of its parameter
groups, what each predicate implies about the continuous values of its arguments (values read from the
belief state, ranges, scene objects), and the ranges of each PDDL type that apply where no predicate says
anything. Its `[refinement]` table sets refinement's defaults (the meta filter, the neighbourhood, the zero
baseline), its `[evaluation]` table which random situations `tailor evaluate` draws (both typed here, once, when
the file is read), its `[training]` table what `tailor train` learns (validated by learning.recipe against
the feature spaces), and its `[objective]` table what refinement minimizes by default: a weight per measure
(`duration = 1.0`, `energy = 0.3`; objective_grammar), the predicted duration alone where it has none.
Binding a domain needs no Python.
"""

from __future__ import annotations

import logging
import math
import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

from tailor.errors import BindingError, SimError, TailorError, check_path_argument
from tailor.planner_bridge.reading import read_input
from tailor.refinement.binding_domain import (DomainVocabulary, check_against_domain, did_you_mean, read_vocabulary,
                                              vocabulary_of)
from tailor.refinement.objective_grammar import DURATION, DURATION_ONLY, WeightedObjective, objective_from_table
from tailor.sims import registry
from tailor.sims.episode import ENERGY, ERROR, HEADING_ERROR
from tailor.sims.protocol import GROUPS, ActionSpec, SimulatorEntry

SCHEMA = 2  # 2: the binding names its simulator
BINDING_FILE = "actions.toml"
DOMAIN_FILE = "domain.pddl"  # the PDDL domain beside it, which the binding is checked against
DEFAULT_TYPE = "default"  # [types.default]: ranges for objects of a type the binding does not name
MAX_BOUND = 1e9  # no bound of a range beyond this: features of larger values overflow (squares, products)
NAMED_BOUNDS = {"pi": math.pi, "-pi": -math.pi}  # strings a range bound may be written as
MEASURES = (ENERGY, ERROR, HEADING_ERROR)  # measures besides the duration that episodes report (sims.episode)

Range = tuple[float, float]

_TOML_WHERE = re.compile(r"^(?P<msg>.*) \(at line (?P<line>\d+), column (?P<col>\d+)\)$")
MAX_TOML_BYTES = 4 * 2**20  # a binding or a belief of thousands of objects is a few hundred kB
MAX_TOML_NESTING = 32  # levels of lists and inline tables, and parts of a dotted key
TOML_INTEGERS = range(-2**63, 2**63)  # "arbitrary 64-bit signed integers" (TOML 1.0); others are an error
_OUT_OF_RANGE = "an integer outside TOML's 64-bit range (-2**63 .. 2**63 - 1)"
_LONG_INTEGER = re.compile(r"(?<![\w.])[+-]?\d[\d_]{19,}(?![\w.])")
# the tokens that matter for nesting: strings (skipped: their brackets and dots are text), comments, brackets,
# dots and the bare words between them (keys, numbers)
_TOML_TOKEN = re.compile(r"""
    (?P<text> \"\"\"(?:\\.|[^\\])*?\"{3,5}  |  \'\'\'.*?\'{3,5}  |  "(?:\\.|[^"\\\n])*"  |  '[^'\n]*' )
  | (?P<comment> \#[^\n]* )
  | (?P<open> [\[{] ) | (?P<close> [\]}] ) | (?P<dot> \. ) | (?P<blank> [\ \t]+ )
  | (?P<word> [\w+-]+ )
  | (?P<other> . )
""", re.DOTALL | re.VERBOSE)


def read_toml(path: Path, error: type[TailorError], what: str) -> dict[str, Any]:
    """Parse a TOML file, turning a missing file or a syntax error into `error` naming the file and line.

    A hostile file ends in the same one line: only a regular file of at most MAX_TOML_BYTES is read (a FIFO or
    /dev/zero would block or never end); lists and inline tables nested deeper than MAX_TOML_NESTING, or keys
    of more dotted parts, are refused before tomllib sees them (it recurses into each level, and takes time
    and memory quadratic in a key's parts); an integer outside TOML's 64-bit range is refused as the TOML
    specification asks (a 5,000-digit one is more than Python will convert; 10**400 no float can hold)."""
    file = str(path)
    data = read_input(Path(path), MAX_TOML_BYTES, error, f"{what} file not found")
    try:
        text = data.decode("utf-8").removeprefix("\ufeff")  # (a byte-order mark, as editors on Windows write)
    except UnicodeDecodeError as exc:
        raise error(f"cannot read {what} file: not UTF-8 text (byte {exc.start})", file=file) from None
    _check_toml_nesting(text, error, file)
    try:
        parsed = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        where = _TOML_WHERE.match(str(exc))
        if where:
            raise error(f"invalid TOML: {where['msg']}", file=file, line=int(where["line"]),
                        col=int(where["col"])) from None
        raise error(f"invalid TOML: {exc}", file=file) from None
    except RecursionError:  # (nesting is checked above: a deep caller's stack)
        raise error("invalid TOML: nested too deeply", file=file) from None
    except ValueError:  # int() refuses more than sys.get_int_max_str_digits() digits
        long = _LONG_INTEGER.search(text)
        line, col = _place(text, long.start()) if long else (None, None)
        raise error(f"invalid TOML: {_OUT_OF_RANGE}", file=file, line=line, col=col) from None
    _check_integers(parsed, error, file)
    return parsed


def _place(text: str, index: int) -> tuple[int, int]:
    """(line, column), 1-based, of text[index]."""
    line = text.count("\n", 0, index) + 1
    return line, index - (text.rfind("\n", 0, index) + 1) + 1


def _check_toml_nesting(text: str, error: type[TailorError], file: str) -> None:
    """An `error` at the place where lists or inline tables nest deeper than MAX_TOML_NESTING, or where a
    dotted key has more parts than that (strings and comments skipped)."""
    depth = parts = 0
    after_dot = False
    for token in _TOML_TOKEN.finditer(text):
        kind = token.lastgroup
        if kind == "blank":
            continue
        if kind == "dot":
            after_dot = parts > 0
            continue
        if kind == "open":
            depth += 1
            parts = 0
            if depth > MAX_TOML_NESTING:
                raise error(f"invalid TOML: lists or inline tables nested deeper than {MAX_TOML_NESTING} levels",
                            file, *_place(text, token.start()))
        elif kind == "close":
            depth = max(0, depth - 1)
            parts = 0
        elif kind in ("text", "word"):  # a part of a key (or a value: a float is two parts, 1.5)
            parts = parts + 1 if after_dot else 1
            if parts > MAX_TOML_NESTING:
                raise error(f"invalid TOML: a dotted key of more than {MAX_TOML_NESTING} parts",
                            file, *_place(text, token.start()))
        else:  # a comment, a line's end, `=`, `,`: no key continues past it
            parts = 0
        after_dot = False


def _check_integers(data: Any, error: type[TailorError], file: str) -> None:
    """An `error` naming the key of the first integer outside TOML_INTEGERS (walked without recursion)."""
    pending = [(data, "")]
    while pending:
        value, key = pending.pop()
        if isinstance(value, dict):
            pending.extend((item, f"{key}.{name}" if key else str(name)) for name, item in value.items())
        elif isinstance(value, list):
            pending.extend((item, f"{key}[{i}]") for i, item in enumerate(value))
        elif isinstance(value, int) and not isinstance(value, bool) and value not in TOML_INTEGERS:
            raise error(f"invalid TOML: {key} is {_OUT_OF_RANGE}", file=file)


@dataclass(frozen=True)
class ActionBinding:
    """A PDDL action bound to an executable action; `args`: parameter group -> index of the PDDL argument.

    `success_model`: the learned success classifier of the executable action for this action's refined goal
    (Ch. 6: reaching an object's pose without bumping it is a navigation to that pose), a file
    `models/<success_model>.collision.json`; where it predicts failure, subgoal assertion (Alg. 5) inserts a
    subgoal and a second action, and refinement keeps the action inside its predicted-success region (Alg. 6).
    `subgoal`: ranges of the asserted subgoal's quantities where they differ from the type defaults (e.g. the
    speeds the action's models were trained for). `success_margin`: a chosen parameterization is valid only if
    success is also predicted this share of each free parameter's range to either side (an optimizer otherwise
    picks the very edge of the predicted-success region, where the classifier is least right).
    """

    pddl: str
    executable: str
    args: Mapping[str, int]
    spec: ActionSpec
    success_model: str | None = None
    subgoal: Mapping[str, Range] = field(default_factory=dict)  # ranges of an asserted subgoal's quantities
    success_margin: float = 0.0  # the success prediction must hold this share of each free range around a choice


@dataclass(frozen=True)
class PredicateBinding:
    """What a predicate implies about the continuous values of the objects it names.

    `read`: quantities taken from the belief state when the fact holds in the initial state (causal link
    from step 0); `ranges`: the interval each quantity lies in whenever the fact holds; `scene`: the scene
    object the fact places when it holds initially; `args`: the argument positions it applies to (None: all);
    `lost_on_failure`: closed-loop execution (tailor.refinement.execution) takes a fact of this predicate that a
    failed action needed to be false afterwards, and what the step that made it true deleted to hold again (the
    robot that lost what it carried no longer has it, and stands where it stood: it must fetch it again).
    """

    name: str
    read: tuple[str, ...]
    ranges: Mapping[str, Range]
    scene: str | None
    args: tuple[int, ...] | None
    lost_on_failure: bool = False

    def objects(self, fact: Sequence[str], file: str | None) -> tuple[str, ...]:
        """The objects of `fact` (predicate name first) this binding speaks about."""
        arguments = tuple(fact[1:])
        if self.args is None:
            return arguments
        for index in self.args:
            if index >= len(arguments):
                raise BindingError(f"[predicates.{self.name}] args index {index} is out of range for "
                                   f"({' '.join(fact)}) with {len(arguments)} argument(s)", file=file)
        return tuple(arguments[i] for i in self.args)


@dataclass(frozen=True)
class RefinementDefaults:
    """The `[refinement]` table: what refinement does unless a command or call says otherwise."""

    filter: bool = False  # refine only where the meta action model (models/meta.json) predicts "better" (Sec. 5.5.4)
    neighbourhood: float = 0.0  # share of each free range whose worst predicted time refinement minimizes
    zero_baseline: bool = False  # also execute every free parameter at 0 (e.g. stop at every way-point)


@dataclass(frozen=True)
class EvaluationPlan:
    """The `[evaluation]` table: the simulator's situation generators `tailor evaluate` draws from."""

    comparison: str  # greedy vs refined (Tables 5.1, 5.4)
    horizons: str | None = None  # the horizon experiment (Table 5.3)
    assertion: str | None = None  # subgoal assertion (Table 6.1, `--assertion`)


REFINEMENT_KEYS = ("filter", "neighbourhood", "zero_baseline")
EVALUATION_KEYS = ("comparison", "horizons", "assertion")


@dataclass(frozen=True)
class Binding:
    """The action library binding of one domain."""

    file: str | None
    domain: str | None
    simulator: str
    actions: Mapping[str, ActionBinding]
    predicates: Mapping[str, PredicateBinding]
    types: Mapping[str, Mapping[str, Range]]
    training: Mapping[str, Any] = field(default_factory=dict)  # raw [training] (tailor.refinement.learning.recipe)
    evaluation: EvaluationPlan | None = None  # None: the binding names no situations to evaluate on
    quantities: tuple[str, ...] = ()  # every quantity the simulator's actions take
    refinement: RefinementDefaults = RefinementDefaults()
    objective: WeightedObjective = DURATION_ONLY  # the [objective] table: what refinement minimizes by default

    @property
    def entry(self) -> SimulatorEntry:
        """The simulator the domain's executable actions run in."""
        return registry.get(self.simulator)

    def action(self, name: str, step: str = "") -> ActionBinding:
        """The binding of PDDL action `name`; a BindingError naming it if the binding does not bind it."""
        try:
            return self.actions[name.lower()]
        except KeyError:
            where = f"plan step {step}: " if step else ""
            raise BindingError(f"{where}PDDL action '{name}' is not bound (add an [actions.{name.lower()}] "
                               "table)", file=self.file) from None

    def require_evaluation(self) -> EvaluationPlan:
        """The `[evaluation]` table; a BindingError naming the file where the binding has none."""
        if self.evaluation is None:
            raise BindingError("[evaluation] missing: the domain's binding names no situations to evaluate on (add "
                               "an [evaluation] table)", file=self.file)
        return self.evaluation

    def predicate(self, name: str) -> PredicateBinding | None:
        """The binding of a predicate, or None: a predicate the binding does not name constrains nothing."""
        return self.predicates.get(name.lower())

    def type_range(self, types: Sequence[str], quantity: str) -> tuple[Range, str] | None:
        """The default range of `quantity` along `types` (most specific first), and the table it came from."""
        for name in types:
            table = self.types.get(name)
            if table is not None and quantity in table:
                return table[quantity], f"[types.{name}]"
        return None


def load_binding(path: Path | str) -> Binding:
    """Read and validate an action library binding file."""
    file = str(path)
    data = read_toml(Path(path), BindingError, "action library binding")
    return parse_binding(data, file)


def load_domain_binding(domain_dir: Path | str, domain_file: Path | str | None = None, signature=None,
                        vocabulary: DomainVocabulary | None = None) -> Binding:
    """The binding of the domain in `domain_dir` (its `actions.toml`), checked against the PDDL domain: its
    `signature` where the caller has read and checked the domain already (planner_bridge.read_pddl), or its
    `vocabulary` where the caller has read it lightly, else a light read of the file `domain_file` (default:
    `domain_dir/domain.pddl` where it exists): no table names what the domain lacks."""
    check_path_argument(domain_dir, "domain_dir")
    binding = load_binding(Path(domain_dir) / BINDING_FILE)
    if signature is not None:
        vocabulary = vocabulary_of(signature)
    elif vocabulary is None:
        domain_file = Path(domain_dir) / DOMAIN_FILE if domain_file is None else Path(domain_file)
        vocabulary = read_vocabulary(domain_file) if domain_file.is_file() else None
    if vocabulary is not None:  # where the read failed, the planner reports the fault with its place
        check_against_domain(binding, vocabulary, DEFAULT_TYPE)
    return binding


def parse_binding(data: Mapping[str, Any], file: str | None = None) -> Binding:
    """Validate the parsed TOML of a binding; every problem is a one-line BindingError naming `file`."""

    def fail(message: str) -> BindingError:
        return BindingError(message, file=file)

    _check_keys(data, {"schema", "domain", "simulator", "actions", "predicates", "types", "training", "evaluation",
                       "refinement", "objective"}, "top level", fail)
    if data.get("schema", SCHEMA) != SCHEMA:
        raise fail(f"unsupported schema {data['schema']!r} (expected {SCHEMA}: a binding names its simulator)")
    domain = data.get("domain")
    if domain is not None and not isinstance(domain, str):
        raise fail("'domain' must be a string")
    simulator = data.get("simulator")
    if simulator is None:
        raise fail("missing 'simulator': the name of the simulator whose actions the domain binds "
                   "(see `tailor domains`)")
    if not isinstance(simulator, str) or not simulator:
        raise fail(f"simulator = {simulator!r} must name a simulator (a string; see `tailor domains`)")
    try:
        entry = registry.get(simulator)
    except SimError as exc:
        raise fail(f"simulator = {simulator!r}: {exc.message}") from None
    quantities = entry.quantities
    actions = {name.lower(): _action(name, table, entry, fail) for name, table in _tables(data, "actions", fail)}
    predicates = {name.lower(): _predicate(name, table, entry, fail)
                  for name, table in _tables(data, "predicates", fail)}
    types = {name: MappingProxyType(_ranges(f"[types.{name}]", table, set(), quantities, fail))
             for name, table in _tables(data, "types", fail)}
    extra = {}
    for key in ("training", "evaluation", "refinement", "objective"):
        if not isinstance(data.get(key, {}), dict):
            raise fail(f"'{key}' must be a table ([{key}])")
        extra[key] = dict(data.get(key, {}))
    refinement = _refinement(extra["refinement"], extra["evaluation"], file, fail)
    evaluation = _evaluation(extra["evaluation"], entry, fail)
    objective = _objective(extra["objective"], entry, fail) if "objective" in data else DURATION_ONLY
    return Binding(file, domain, simulator, MappingProxyType(actions), MappingProxyType(predicates),
                   MappingProxyType(types), MappingProxyType(extra["training"]), evaluation, quantities, refinement,
                   objective)


def known_measures(entry: SimulatorEntry) -> tuple[str, ...]:
    """The measures of the simulator `entry`'s actions: the duration, and each of MEASURES it declares a unit for
    (its episodes report those)."""
    return (DURATION, *(name for name in MEASURES if name in entry.units))


def _objective(table: dict, entry: SimulatorEntry, fail) -> WeightedObjective:
    """The [objective] table: measure = weight, each a measure of the simulator, weights >= 0, one above 0."""
    known = known_measures(entry)
    for measure in table:
        if measure not in known:
            raise fail(f"[objective] {measure!r} is not a measure of simulator {entry.name!r} (known: "
                       f"{', '.join(known)}){_did_you_mean(measure, known)}")
    try:
        return objective_from_table(table)
    except ValueError as exc:
        raise fail(f"[objective] {exc}") from None


def _refinement(table: dict, evaluation: dict, file: str | None, fail) -> RefinementDefaults:
    """The [refinement] table; its keys are still read from [evaluation], where bindings before it had them
    (with a warning: each key belongs in one place)."""
    _check_keys(table, set(REFINEMENT_KEYS), "[refinement]", fail)
    values = dict(table)
    for key in REFINEMENT_KEYS:
        if key in evaluation:
            if key in table:
                raise fail(f"[evaluation] {key} and [refinement] {key} both given: keep the one in [refinement]")
            logging.getLogger(__name__).warning("%s: [evaluation] %s is a refinement default: move it to "
                                                "[refinement]", file or "<binding>", key)
            values[key] = evaluation[key]
    for key in ("filter", "zero_baseline"):
        if not isinstance(values.get(key, False), bool):
            raise fail(f"[refinement] {key} must be true or false, not {values[key]!r}")
    neighbourhood = values.get("neighbourhood", 0.0)
    if isinstance(neighbourhood, bool) or not isinstance(neighbourhood, (int, float)) or not 0.0 <= neighbourhood < 0.5:
        raise fail(f"[refinement] neighbourhood must be a share of each free range in [0, 0.5), not {neighbourhood!r}")
    return RefinementDefaults(values.get("filter", False), float(neighbourhood), values.get("zero_baseline", False))


def _evaluation(table: dict, entry: SimulatorEntry, fail) -> EvaluationPlan | None:
    """The [evaluation] table, its situation generators checked against the simulator's; None where it is absent."""
    table = {k: v for k, v in table.items() if k not in REFINEMENT_KEYS}  # (read by _refinement)
    if not table:
        return None
    for key in table:
        if key not in EVALUATION_KEYS:
            raise fail(f"[evaluation] unknown key '{key}' (expected {', '.join(EVALUATION_KEYS)}; "
                       f"{', '.join(REFINEMENT_KEYS)} belong in [refinement])")
    known = entry.situations
    for key in EVALUATION_KEYS:
        value = table.get(key)
        if value is None and key != "comparison":
            continue
        if not isinstance(value, str) or value not in known:
            raise fail(f"[evaluation] {key} = {value!r} is not a situation generator of simulator {entry.name!r} "
                       f"(known: {', '.join(known) or 'none'})")
    return EvaluationPlan(table["comparison"], table.get("horizons"), table.get("assertion"))


def _tables(data: Mapping[str, Any], key: str, fail) -> list[tuple[str, Mapping[str, Any]]]:
    section = data.get(key, {})
    if not isinstance(section, dict):
        raise fail(f"'{key}' must be a table of tables ([{key}.NAME])")
    for name, table in section.items():
        if not isinstance(table, dict):
            raise fail(f"[{key}.{name}] must be a table")
    return list(section.items())


def _check_keys(table: Mapping[str, Any], allowed: set[str], where: str, fail) -> None:
    for key in table:
        if key not in allowed:
            raise fail(f"{where}: unknown key '{key}' (expected one of {', '.join(sorted(allowed))})"
                       f"{_did_you_mean(key, allowed)}")


def _did_you_mean(name: str, known) -> str:
    return did_you_mean(name, known)


def _index(where: str, value: Any, fail) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise fail(f"{where} must be a PDDL argument index (an integer >= 0), not {value!r}")
    return value


def _action(name: str, table: Mapping[str, Any], entry: SimulatorEntry, fail) -> ActionBinding:
    where = f"[actions.{name}]"
    _check_keys(table, {"executable", "success_model", "subgoal", "success_margin", *GROUPS}, where, fail)
    executable = table.get("executable")
    if executable is None:
        raise fail(f"{where} missing 'executable': the action of simulator {entry.name!r} it runs "
                   f"(known: {', '.join(entry.actions)})")
    if not isinstance(executable, str) or executable not in entry.actions:
        hint = _did_you_mean(executable, entry.actions) if isinstance(executable, str) else ""
        raise fail(f"{where} executable = {executable!r} is not an executable action of simulator "
                   f"{entry.name!r} (known: {', '.join(entry.actions)}){hint}")
    spec = entry.actions[executable]
    args = {}
    for group in GROUPS:
        has_parameters = bool(getattr(spec, group))
        if group in table and not has_parameters:
            raise fail(f"{where} {group}: {executable} has no {group} parameters")
        if has_parameters:
            if group not in table:
                raise fail(f"{where} missing '{group}': the PDDL argument index that supplies "
                           f"{executable}'s {group} parameters {', '.join(getattr(spec, group))}")
            args[group] = _index(f"{where} {group}", table[group], fail)
    success_model = table.get("success_model")
    if success_model is not None and (not isinstance(success_model, str) or not success_model.strip()):
        raise fail(f"{where} success_model must name a success classifier file "
                   f"(models/<name>.collision.json), not {success_model!r}")
    if success_model is not None and not {"observed", "internal"} <= set(args):
        raise fail(f"{where} success_model: subgoal assertion needs an action with observed and internal "
                   f"parameters (a start and a subgoal); {executable} has {', '.join(args) or 'none'}")
    if success_model is not None and not set(spec.observed_quantities) <= set(spec.internal_quantities):
        raise fail(f"{where} success_model: an asserted subgoal is reached and left by {executable}, so its start "
                   f"quantities ({', '.join(spec.observed_quantities)}) must be among its goal quantities "
                   f"({', '.join(spec.internal_quantities)})")
    subgoal = table.get("subgoal", {})
    if not isinstance(subgoal, dict):
        raise fail(f"{where} subgoal must be a table of ranges, e.g. subgoal = {{ v = [0.0, 0.6] }}")
    if subgoal and success_model is None:
        raise fail(f"{where} subgoal: ranges of an asserted subgoal need a success_model (nothing is asserted)")
    subgoal = _ranges(f"{where} subgoal", subgoal, set(), spec.internal_quantities, fail)
    margin = table.get("success_margin", 0.0)
    if isinstance(margin, bool) or not isinstance(margin, (int, float)) or not 0.0 <= margin < 0.5:
        raise fail(f"{where} success_margin must be a share of a free range in [0, 0.5), not {margin!r}")
    if margin and success_model is None:
        raise fail(f"{where} success_margin needs a success_model")
    return ActionBinding(name.lower(), executable, MappingProxyType(args), spec, success_model,
                         MappingProxyType(subgoal), float(margin))


def _predicate(name: str, table: Mapping[str, Any], entry: SimulatorEntry, fail) -> PredicateBinding:
    quantities = entry.quantities
    where = f"[predicates.{name}]"
    extra = {"read", "scene", "args", "lost_on_failure"}
    lost = table.get("lost_on_failure", False)
    if not isinstance(lost, bool):
        raise fail(f"{where} lost_on_failure must be true or false, not {lost!r}")
    read = table.get("read", [])
    if not isinstance(read, list) or not all(isinstance(q, str) for q in read):
        raise fail(f"{where} read must be a list of quantity names")
    for quantity in read:
        if quantity not in quantities:
            raise fail(f"{where} read: unknown quantity '{quantity}' (known: {', '.join(quantities)})")
    if len(set(read)) != len(read):
        raise fail(f"{where} read names a quantity twice")
    scene = table.get("scene")
    if scene is not None and (not isinstance(scene, str) or not scene):
        raise fail(f"{where} scene must be the name of a scene object, e.g. \"robot\"")
    if scene is not None and entry.scene_objects and scene not in entry.scene_objects:
        raise fail(f"{where} scene = {scene!r} is not a scene object of simulator {entry.name!r} "
                   f"(known: {', '.join(entry.scene_objects)})")
    if scene is not None and not read:
        raise fail(f"{where} scene = {scene!r} needs a read list (the quantities that place the {scene})")
    args = table.get("args")
    if args is not None:
        if not isinstance(args, list) or not args:
            raise fail(f"{where} args must be a non-empty list of argument indices")
        args = tuple(_index(f"{where} args", a, fail) for a in args)
    ranges = _ranges(where, table, extra, quantities, fail)
    return PredicateBinding(name.lower(), tuple(read), MappingProxyType(ranges), scene, args, lost)


def _ranges(where: str, table: Mapping[str, Any], extra: set[str], quantities: tuple[str, ...],
            fail) -> dict[str, Range]:
    ranges = {}
    for key, value in table.items():
        if key in extra:
            continue
        if key not in quantities:
            allowed = ", ".join([*sorted(extra), *quantities])
            raise fail(f"{where}: unknown key '{key}' (expected one of {allowed})"
                       f"{_did_you_mean(key, [*extra, *quantities])}")
        ranges[key] = _range(f"{where} {key}", value, fail)
    return ranges


def _range(where: str, value: Any, fail) -> Range:
    if not isinstance(value, list) or len(value) != 2:
        raise fail(f"{where} must be a range [low, high], not {value!r}")
    low, high = (_bound(where, v, fail) for v in value)
    if low > high:
        raise fail(f"{where} = [{low:g}, {high:g}] is empty (low > high)")
    return low, high


def _bound(where: str, value: Any, fail) -> float:
    if isinstance(value, str) and value.strip().lower() in NAMED_BOUNDS:
        return NAMED_BOUNDS[value.strip().lower()]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise fail(f"{where}: {value!r} is not a number (or \"pi\" / \"-pi\")")
    if not math.isfinite(value):
        raise fail(f"{where}: {value!r} is not a finite number")
    if abs(value) > MAX_BOUND:
        raise fail(f"{where}: {value!r} is beyond {MAX_BOUND:g} (a range a robot's parameter could take)")
    return float(value)
