"""Ground a typed STRIPS problem (negative preconditions, equality) for the POCL planner (planner_bridge.pocl).

Facts are numbered; a literal is `2 * fact` (the fact holds) or `2 * fact + 1` (it does not), so `literal ^ 1`
is its negation. Only actions reachable in the relaxed problem (deletes ignored) are grounded; preconditions
on static facts (no action changes them) are kept apart: the initial state supports them and nothing can
threaten them. The world is closed: the initial state supports the negation of every fact it lacks, a static
one included, so `(not (closed ?p))` holds forever of every port the initial state does not close.
"""

from __future__ import annotations

from dataclasses import dataclass

Fact = tuple[str, ...]


def positive(fact: int) -> int:
    return 2 * fact


def negative(fact: int) -> int:
    return 2 * fact + 1


@dataclass(frozen=True)
class GroundAction:
    """One ground action: `preconditions` need a causal link, `static` hold initially and forever;
    `conditions` lists both in the order the PDDL action writes them."""

    name: str
    args: tuple[str, ...]
    preconditions: tuple[int, ...]
    static: tuple[int, ...]
    conditions: tuple[int, ...]
    effects: frozenset[int]  # the literals the action makes true (adds as positive, deletes as negative)


@dataclass(frozen=True)
class GroundTask:
    """The ground problem: facts by number, the initial facts, the goal literals and the actions."""

    facts: tuple[Fact, ...]
    initial: frozenset[int]
    goal: tuple[int, ...]
    actions: tuple[GroundAction, ...]

    def initially(self, literal: int) -> bool:
        """Whether `literal` holds in the initial state (closed world: an unlisted fact is false)."""
        return ((literal >> 1) in self.initial) != bool(literal & 1)

    def literal_text(self, literal: int) -> str:
        atom = "(" + " ".join(self.facts[literal >> 1]) + ")"
        return f"(not {atom})" if literal & 1 else atom


class UnsupportedCondition(ValueError):
    """A condition or effect that is not a literal of typed STRIPS (the engine's supported kind excludes it)."""


def _template(node):
    """(fluent name, argument templates) of a fluent expression: a parameter name or ("object", name)."""
    if not node.is_fluent_exp():
        raise UnsupportedCondition(f"not a fluent: {node}")
    args = []
    for arg in node.args:
        if arg.is_parameter_exp():
            args.append(arg.parameter().name)
        elif arg.is_object_exp():
            args.append(("object", arg.object().name))
        else:
            raise UnsupportedCondition(f"argument {arg} of {node}")
    return node.fluent().name, tuple(args)


def _literals(node, out: list) -> list:
    """Flatten a conjunction into (kind, template) with kind "+", "-" or "=" (an equality, "!=" negated)."""
    if node.is_and():
        for arg in node.args:
            _literals(arg, out)
    elif node.is_bool_constant():
        if not node.bool_constant_value():
            out.append(("false", None))
    elif node.is_not() and node.arg(0).is_equals():
        out.append(("!=", tuple(_template_arg(a) for a in node.arg(0).args)))
    elif node.is_equals():
        out.append(("=", tuple(_template_arg(a) for a in node.args)))
    elif node.is_not():
        out.append(("-", _template(node.arg(0))))
    else:
        out.append(("+", _template(node)))
    return out


def _template_arg(arg):
    if arg.is_parameter_exp():
        return arg.parameter().name
    if arg.is_object_exp():
        return ("object", arg.object().name)
    raise UnsupportedCondition(f"equality over {arg}")


def _bind(template, binding: dict) -> Fact:
    name, args = template
    return (name, *(a[1] if isinstance(a, tuple) else binding[a] for a in args))


class _Schema:
    """An action's parameters with their objects, its precondition and effect templates."""

    def __init__(self, problem, action):
        self.name = action.name
        self.parameters = [p.name for p in action.parameters]
        self.domains = {p.name: [o.name for o in problem.objects(p.type)] for p in action.parameters}
        self.conditions = []
        for condition in action.preconditions:
            _literals(condition, self.conditions)
        self.adds, self.deletes = [], []
        for effect in action.effects:
            if effect.is_conditional() or effect.is_forall() or not effect.value.is_bool_constant():
                raise UnsupportedCondition(f"effect {effect} of {action.name}")
            (self.adds if effect.value.bool_constant_value() else self.deletes).append(_template(effect.fluent))


def _holds(kind: str, template, binding: dict, reached, static_true) -> bool:
    """Whether a precondition can hold in the relaxed problem under the (complete for it) binding: a positive
    one when its fact is reached, a negative one unless its fact is static and true initially (then forever)."""
    if kind == "false":
        return False
    if kind in ("=", "!="):
        left, right = (a[1] if isinstance(a, tuple) else binding[a] for a in template)
        return (left == right) == (kind == "=")
    if kind == "+":
        return _bind(template, binding) in reached
    return _bind(template, binding) not in static_true


def _bindings(schema: _Schema, reached: set, by_name: dict, static_true):
    """Every binding of the schema's parameters that satisfies its relaxed preconditions, in a fixed order."""
    checks = list(schema.conditions)
    positives = [t for k, t in checks if k == "+"]

    def params_of(kind, template) -> set:
        args = template[1] if kind in ("+", "-") else template if kind in ("=", "!=") else ()
        return {a for a in args if not isinstance(a, tuple)}

    def extend(binding: dict, index: int):
        if index < len(positives):  # join the next positive precondition with the reached facts
            name, args = positives[index]
            for fact in by_name.get(name, ()):
                new = dict(binding)
                if all(_unify(a, value, new, schema.domains) for a, value in zip(args, fact[1:])):
                    yield from extend(new, index + 1)
            return
        free = [p for p in schema.parameters if p not in binding]
        if free:
            for value in schema.domains[free[0]]:
                yield from extend({**binding, free[0]: value}, index)
            return
        if all(_holds(k, t, binding, reached, static_true) for k, t in checks if params_of(k, t) <= binding.keys()):
            yield tuple(binding[p] for p in schema.parameters)

    yield from extend({}, 0)


def _unify(template_arg, value: str, binding: dict, domains: dict) -> bool:
    if isinstance(template_arg, tuple):
        return template_arg[1] == value
    if template_arg in binding:
        return binding[template_arg] == value
    if value not in domains[template_arg]:
        return False
    binding[template_arg] = value
    return True


def ground(problem) -> GroundTask:
    """The reachable ground actions of a typed STRIPS problem, with facts and literals numbered."""
    schemas = [_Schema(problem, action) for action in problem.actions]
    changing = {t[0] for s in schemas for t in s.adds + s.deletes}
    initial_facts = [
        (fluent.fluent().name, *(a.object().name for a in fluent.args))
        for fluent, value in problem.explicit_initial_values.items()
        if value.is_true()
    ]
    initial_set = set(initial_facts)

    class _StaticTrue:
        """The facts no action changes that hold initially: true forever, so their negations never hold.
        (A static fact the initial state lacks is false forever: its negation always holds.)"""

        def __contains__(self, fact) -> bool:
            return fact[0] not in changing and fact in initial_set

    static_true = _StaticTrue()
    reached, by_name = set(initial_facts), {}
    for fact in initial_facts:
        by_name.setdefault(fact[0], []).append(fact)
    grounded: dict[tuple[int, tuple[str, ...]], None] = {}
    changed = True
    while changed:  # relaxed reachability: apply every applicable action's adds until nothing new is reached
        changed = False
        for number, schema in enumerate(schemas):
            for args in list(_bindings(schema, reached, by_name, static_true)):
                if (number, args) in grounded:
                    continue
                grounded[(number, args)] = None
                binding = dict(zip(schema.parameters, args))
                for template in schema.adds:
                    fact = _bind(template, binding)
                    if fact not in reached:
                        reached.add(fact)
                        by_name.setdefault(fact[0], []).append(fact)
                        changed = True
    return _number(problem, schemas, sorted(grounded), initial_facts, changing)


def _number(problem, schemas, grounded, initial_facts, changing) -> GroundTask:
    """Number the facts and build the ground actions and goal as literals."""
    index: dict[Fact, int] = {}

    def fact_number(fact: Fact) -> int:
        return index.setdefault(fact, len(index))

    initial = frozenset(fact_number(f) for f in initial_facts)
    actions = []
    for number, args in grounded:
        schema = schemas[number]
        binding = dict(zip(schema.parameters, args))
        needs, static, conditions = [], [], []
        for kind, template in schema.conditions:
            if kind not in ("+", "-"):
                continue  # equalities were decided while grounding
            fact = _bind(template, binding)
            literal = positive(fact_number(fact)) if kind == "+" else negative(fact_number(fact))
            target = static if fact[0] not in changing else needs
            if literal not in target:
                target.append(literal)
                conditions.append(literal)
        adds = {fact_number(_bind(t, binding)) for t in schema.adds}
        deletes = {fact_number(_bind(t, binding)) for t in schema.deletes} - adds  # PDDL: adds win
        effects = frozenset({positive(f) for f in adds} | {negative(f) for f in deletes})
        if any(literal ^ 1 in needs for literal in needs) or effects <= set(needs):
            continue  # contradictory preconditions, or a step that changes nothing: never needed in a plan
        actions.append(GroundAction(schema.name, args, tuple(needs), tuple(static), tuple(conditions), effects))
    goal: list[int] = []
    for kind, template in (lit for g in problem.goals for lit in _literals(g, [])):
        if kind not in ("+", "-"):
            raise UnsupportedCondition(f"goal condition {kind} {template}")
        fact = _bind(template, {})
        literal = positive(fact_number(fact)) if kind == "+" else negative(fact_number(fact))
        if literal not in goal:
            goal.append(literal)
    facts = tuple(sorted(index, key=index.get))
    return GroundTask(facts, initial, tuple(goal), tuple(actions))
