"""Semantic checks of a domain/problem pair before unified-planning reads it.

unified-planning reports some of these mistakes with an unclear message or none at all (an undefined type in
a problem, a problem written for another domain), so we check them here, each naming the file, line and column:
undefined predicates, types, objects and variables, wrong arity, and a problem naming another domain.
Requirements the reader does not know or support are named. Only the usual PDDL subset is checked; anything unfamiliar is left for the PDDL reader to judge.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from tailor.errors import PDDLSemanticError, PDDLSyntaxError, PlannerUnavailableError
from tailor.planner_bridge.sexpr import Expr, SList, Symbol

CONNECTIVES = {"and", "or", "not", "imply"}
QUANTIFIERS = {"forall", "exists"}
NUMERIC = {"=", "<", ">", "<=", ">=", "increase", "decrease", "assign", "scale-up", "scale-down"}
SKIPPED = {"preference"}  # PDDL3 preferences: left to the reader
BUILTIN_TYPES = frozenset({"object", "number"})
# Requirements unified-planning's PDDL reader accepts (its grammar lists them; any other stops it with an
# unhelpful "Expected ')'"), and those of PDDL 1.2-3.1 that it does not.
SUPPORTED_REQUIREMENTS = {
    ":strips", ":typing", ":negative-preconditions", ":disjunctive-preconditions", ":equality",
    ":existential-preconditions", ":universal-preconditions", ":quantified-preconditions", ":conditional-effects",
    ":fluents", ":numeric-fluents", ":adl", ":durative-actions", ":duration-inequalities", ":timed-initial-literals",
    ":timed-initial-effects", ":action-costs", ":hierarchy", ":method-preconditions", ":constraints", ":contingent",
    ":preferences", ":time", ":continuous-effects",
}
UNSUPPORTED_REQUIREMENTS = {":derived-predicates", ":object-fluents", ":domain-axioms", ":safety-constraints",
                            ":expression-evaluation", ":open-world", ":true-negation", ":ucpop", ":action-expansions",
                            ":foreach-expansions", ":dag-expansions", ":subgoals-through-axioms", ":multi-agent"}


@dataclass(frozen=True)
class DomainSignature:
    """What a domain declares: its name, types, constants, predicates (name -> arity), function and action names.
    Built once by check_domain and not changed afterwards (the mapping of predicates is not to be written to)."""

    file: str
    name: str = ""
    types: frozenset[str] = BUILTIN_TYPES
    constants: frozenset[str] = frozenset()
    predicates: dict[str, int] = field(default_factory=dict)
    functions: frozenset[str] = frozenset()
    actions: frozenset[str] = frozenset()

    def __hash__(self) -> int:  # (the predicates' dict would make the generated hash fail)
        return hash((self.file, self.name, self.types, self.constants, frozenset(self.predicates.items()),
                     self.functions, self.actions))

    def reserved_names(self) -> dict[str, str]:
        """Lower-cased names an object may not take, with what they name: unified-planning reads one namespace,
        so an object named like a type, predicate, function or action is refused by its reader (with a hint at
        an environment flag that does not help: its reader then takes the object for the predicate)."""
        reserved: dict[str, str] = {}
        for kind, names in (("action", self.actions), ("function", self.functions),
                            ("predicate", self.predicates), ("type", self.types - BUILTIN_TYPES)):
            reserved.update((name.lower(), kind) for name in names)
        return reserved

    def to_json(self) -> dict:
        return {"file": self.file, "name": self.name, "types": sorted(self.types), "constants": sorted(self.constants),
                "predicates": dict(self.predicates), "functions": sorted(self.functions),
                "actions": sorted(self.actions)}

    @classmethod
    def from_json(cls, data: dict) -> "DomainSignature":
        return cls(data["file"], data["name"], frozenset(data["types"]), frozenset(data["constants"]),
                   dict(data["predicates"]), frozenset(data["functions"]), frozenset(data["actions"]))


def _check_object_name(name: Symbol, reserved: dict[str, str], what: str, file: str) -> None:
    """A PDDLSemanticError at the name where an object or constant has a reserved name."""
    kind = reserved.get(name.text.lower())
    if kind is not None:
        article = "an" if kind[0] in "aeiou" else "a"
        raise PDDLSemanticError(f"{what} '{name.text}' has the name of {article} {kind}: unified-planning "
                                "cannot read a problem whose names clash; rename one of them",
                                file, name.line, name.col)


def _sections(define: SList) -> list[SList]:
    return [item for item in define.items[1:] if isinstance(item, SList)]


def _typed_names(items: tuple[Expr, ...]) -> list[tuple[Symbol, Expr | None]]:
    """Split `a b - t c` into [(a, t), (b, t), (c, None)]; a type may be a symbol or (either ...)."""
    result: list[tuple[Symbol, Expr | None]] = []
    pending: list[Symbol] = []
    i = 0
    while i < len(items):
        item = items[i]
        if isinstance(item, Symbol) and item.text == "-" and i + 1 < len(items):
            result.extend((name, items[i + 1]) for name in pending)
            pending, i = [], i + 2
            continue
        if isinstance(item, Symbol):
            pending.append(item)
        i += 1
    result.extend((name, None) for name in pending)
    return result


def _check_type(type_expr: Expr | None, types: frozenset[str] | set[str], file: str) -> None:
    if type_expr is None:
        return
    names = [type_expr] if isinstance(type_expr, Symbol) else [s for s in type_expr.items[1:] if isinstance(s, Symbol)]
    for name in names:
        if name.text not in types:
            raise PDDLSemanticError(f"undefined type '{name.text}'", file, name.line, name.col)


def _render(expr: Expr) -> str:
    if isinstance(expr, Symbol):
        return expr.text
    return "(" + " ".join(_render(item) for item in expr.items) + ")"


def _check_atom(atom: SList, sig: DomainSignature, scope: set[str], objects: set[str], file: str) -> None:
    name = atom.head
    if name is None:
        raise PDDLSyntaxError(f"syntax error: expected a predicate name in {_render(atom)}", file, atom.line, atom.col)
    if name in sig.functions:
        return
    if name not in sig.predicates:
        raise PDDLSemanticError(f"undefined predicate '{name}' in {_render(atom)}", file, atom.line, atom.col)
    args = atom.items[1:]
    if len(args) != sig.predicates[name]:
        raise PDDLSemanticError(
            f"predicate '{name}' takes {sig.predicates[name]} argument(s) but {_render(atom)} gives {len(args)}",
            file, atom.line, atom.col,
        )
    for arg in args:
        if isinstance(arg, SList):
            continue  # a function term: left to the reader
        if arg.text.startswith("?"):
            if arg.text not in scope:
                raise PDDLSemanticError(f"undefined variable '{arg.text}' in {_render(atom)}", file, arg.line, arg.col)
        elif arg.text not in objects:
            raise PDDLSemanticError(f"undefined object '{arg.text}' in {_render(atom)}", file, arg.line, arg.col)


def _check_formula(expr: Expr, sig: DomainSignature, scope: set[str], objects: set[str], file: str) -> None:
    """Walk a condition or effect; check every atom against the domain's predicates."""
    if not isinstance(expr, SList) or not expr.items:
        return  # `()` is the empty condition; a bare symbol is left to the reader
    head, items = expr.head, expr.items
    if head in CONNECTIVES or head == "when":
        for item in items[1:]:
            _check_formula(item, sig, scope, objects, file)
    elif head in QUANTIFIERS and len(items) == 3 and isinstance(items[1], SList):
        variables = _typed_names(items[1].items)
        for _, type_expr in variables:
            _check_type(type_expr, sig.types, file)
        _check_formula(items[2], sig, scope | {v.text for v, _ in variables}, objects, file)
    elif head in ("at", "over") and len(items) == 3 and isinstance(items[1], Symbol) and (
        items[1].text in ("start", "end", "all")
    ):
        _check_formula(items[2], sig, scope, objects, file)  # durative: (at start F), (over all F)
    elif head == "at" and len(items) == 3 and isinstance(items[1], Symbol) and _is_number(items[1].text) and (
        isinstance(items[2], SList)
    ):
        _check_formula(items[2], sig, scope, objects, file)  # a timed initial literal: (at 10 (not (open)))
    elif head in NUMERIC or head in SKIPPED:
        return
    else:
        _check_atom(expr, sig, scope, objects, file)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _check_type_cycles(parents: dict[str, tuple[Symbol, Symbol]], file: str) -> None:
    """A PDDLSemanticError at the declaration of a type that is, through its parents, its own ancestor
    (unified-planning's reader would recurse along the cycle until Python's recursion limit). `parents` maps
    a type to its name where declared and its parent's name there."""
    done: set[str] = set()
    for start in parents:
        path: list[str] = []
        name = start
        while name in parents and name not in done and name not in path:
            path.append(name)
            name = parents[name][1].text
        if name in path:  # back on the path: a cycle from `name`
            cycle = path[path.index(name):] + [name]
            where = parents[cycle[0]][0]
            raise PDDLSemanticError(f"the type hierarchy is cyclic: {' - '.join(cycle)} (each a subtype of the "
                                    "next)", file, where.line, where.col)
        done.update(path)


def _keyword_values(items: tuple[Expr, ...]) -> dict[str, Expr]:
    values: dict[str, Expr] = {}
    for key, value in zip(items, items[1:]):
        if isinstance(key, Symbol) and key.text.startswith(":"):
            values[key.text] = value
    return values


def _check_requirements(sections: list[SList], file: str) -> None:
    """Name a requirement the reader does not know or does not support (it would only say "Expected ')'")."""
    for section in sections:
        if section.head != ":requirements":
            continue
        for item in section.items[1:]:
            text = item.text if isinstance(item, Symbol) else _render(item)
            if text in SUPPORTED_REQUIREMENTS:
                continue
            if text in UNSUPPORTED_REQUIREMENTS:
                raise PlannerUnavailableError(
                    f"requirement {text} is not supported (unified-planning's PDDL reader cannot read it)",
                    file, item.line, item.col,
                )
            raise PDDLSyntaxError(f"syntax error: unknown requirement {text}", file, item.line, item.col)


def check_domain(define: SList, file: str) -> DomainSignature:
    """Check a domain's declarations and action bodies; return what it declares for checking problems."""
    name, types, constants = "", set(BUILTIN_TYPES), []  # constants: where each is declared
    predicates: dict[str, int] = {}
    functions: set[str] = set()
    parents: dict[str, tuple[Symbol, Symbol]] = {}  # a type: its name where declared, and its parent's
    sections = _sections(define)
    _check_requirements(sections, file)
    for section in sections:
        if section.head == "domain" and len(section.items) == 2 and isinstance(section.items[1], Symbol):
            name = section.items[1].text
        elif section.head == ":types":
            for type_name, parent in _typed_names(section.items[1:]):
                types.add(type_name.text)
                if isinstance(parent, Symbol):
                    types.add(parent.text)
                    parents.setdefault(type_name.text, (type_name, parent))
    _check_type_cycles(parents, file)
    for section in sections:
        if section.head == ":constants":
            for constant, type_expr in _typed_names(section.items[1:]):
                _check_type(type_expr, types, file)
                constants.append(constant)
        elif section.head == ":predicates":
            for predicate in section.items[1:]:
                if isinstance(predicate, SList) and predicate.head:
                    params = _typed_names(predicate.items[1:])
                    for _, type_expr in params:
                        _check_type(type_expr, types, file)
                    predicates[predicate.head] = len(params)
        elif section.head == ":functions":
            functions |= {f.head for f in section.items[1:] if isinstance(f, SList) and f.head}
    actions = {section.items[1].text for section in sections
               if section.head in (":action", ":durative-action") and len(section.items) > 1
               and isinstance(section.items[1], Symbol)}
    sig = DomainSignature(file, name, frozenset(types), frozenset(c.text for c in constants), predicates,
                          frozenset(functions), frozenset(actions))
    reserved = sig.reserved_names()
    for constant in constants:  # (checked once every name they may clash with is known)
        _check_object_name(constant, reserved, "constant", file)
    for section in sections:
        if section.head in (":action", ":durative-action"):
            values = _keyword_values(section.items[2:])
            params = values.get(":parameters")
            typed = _typed_names(params.items) if isinstance(params, SList) else []
            for _, type_expr in typed:
                _check_type(type_expr, sig.types, file)
            scope = {param.text for param, _ in typed}
            for key in (":precondition", ":condition", ":effect"):
                if key in values:
                    _check_formula(values[key], sig, scope, sig.constants, file)
        elif section.head == ":derived" and len(section.items) == 3 and isinstance(section.items[1], SList):
            scope = {param.text for param, _ in _typed_names(section.items[1].items[1:])}
            _check_formula(section.items[2], sig, scope, sig.constants, file)
    return sig


def check_problem(define: SList, sig: DomainSignature, file: str) -> str:
    """Check that a problem belongs to the domain and uses only what the domain and its objects declare; return
    the problem's name (lower-cased, as unified-planning's reader names it; "" where it has none)."""
    name = ""
    sections = _sections(define)
    _check_requirements(sections, file)
    objects = set(sig.constants)
    declared = {known.lower() for known in objects}  # (names are case-insensitive)
    reserved = sig.reserved_names()
    for section in sections:
        if section.head == "problem" and len(section.items) == 2 and isinstance(section.items[1], Symbol):
            name = section.items[1].text
        elif section.head == ":domain" and len(section.items) == 2 and isinstance(section.items[1], Symbol):
            named = section.items[1]
            if sig.name and named.text != sig.name:
                raise PDDLSemanticError(
                    f"the problem is for domain '{named.text}', but {sig.file} defines domain '{sig.name}'",
                    file, named.line, named.col,
                )
        elif section.head == ":objects":
            for obj, type_expr in _typed_names(section.items[1:]):
                _check_type(type_expr, sig.types, file)
                _check_object_name(obj, reserved, "object", file)
                if obj.text.lower() in declared:
                    raise PDDLSemanticError(f"object '{obj.text}' is declared twice (or as a constant of the "
                                            "domain)", file, obj.line, obj.col)
                objects.add(obj.text)
                declared.add(obj.text.lower())
    for section in sections:
        if section.head == ":init":
            for fact in section.items[1:]:
                _check_formula(fact, sig, set(), objects, file)
        elif section.head == ":goal":
            for goal in section.items[1:]:
                _check_formula(goal, sig, set(), objects, file)
    return name
