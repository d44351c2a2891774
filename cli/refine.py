"""`tailor refine DOMAIN PROBLEM`: plan, instantiate, refine the free parameters (Sec. 5.4), optionally simulate.

Greedy execution (h = 1) is always computed beside the requested horizon, so the gain can be read off.
`--objective "duration + 0.3*energy"` weighs further measures the action models predict, `--max error=0.05`
bounds them (Ch. 8.1); text and JSON then show every measure predicted (and, simulated, measured) per action,
and a bound no choice keeps ends the command with status 9 after the output, naming the step.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
import time
from pathlib import Path

from tailor.errors import TailorError, UsageError
from tailor.outputs import Provenance, check_output_file, json_text, provenance, versioned
from tailor.planner_bridge import plan_from_ipc, render_text
from tailor.progress import showing_progress
from tailor.refinement import pipeline
from tailor.refinement.models.action_models import COLLISION_SUFFIX
from tailor.refinement.models.meta_model import load_meta_model, meta_model_path
from tailor.refinement.objective_grammar import DURATION, ObjectiveSyntaxError, bounds_of
from tailor.refinement.optimizers import DEFAULT_OPTIMIZER, OPTIMIZERS
from tailor.refinement.refine import predicted_success
from tailor.refinement.refine_plots import cost_plot_names, draw_refinement
from tailor.cli.arguments import (
    add_filter_arguments,
    add_models_argument,
    add_neighbourhood_argument,
    add_objective_arguments,
    add_risk_argument,
    announce_models,
    positive_seconds,
    seed,
    whole_number,
)



def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("domain", metavar="DOMAIN", help="domain.pddl file, the folder holding it, or the name of a bundled domain (see `tailor domains`)")
    parser.add_argument("problem", metavar="PROBLEM", help="problem .pddl file, or the name of one of its problems")
    parser.add_argument("--optimizer", choices=sorted(OPTIMIZERS), default=DEFAULT_OPTIMIZER,
                        help="auto: analytic model-tree minimization where it applies, else the certified branch "
                             "and bound where the feature spaces declare bounds, else the genetic algorithm; or "
                             "one of them alone (analytic and certified fall back to ga), or random sampling "
                             f"(default: {DEFAULT_OPTIMIZER})")
    parser.add_argument("--horizon", type=whole_number(1), default=2, metavar="H",
                        help="actions optimized together (default 2; 1 is greedy)")
    parser.add_argument("--seed", type=seed, default=0, metavar="S", help="seed of optimizer and simulator (default 0)")
    parser.add_argument("--belief", metavar="FILE", help="belief state file (default: PROBLEM's stem + .toml)")
    add_models_argument(parser)
    parser.add_argument("--planner", default="pyperplan", metavar="NAME", help="unified-planning engine, or pocl")
    parser.add_argument("--plan", metavar="FILE", help="refine this plan instead of planning: a sequential IPC plan "
                        "file any planner wrote (Fast Downward's sas_plan, `tailor plan --format ipc`), validated and "
                        "linked first")
    parser.add_argument("--strict", action="store_true", help="the warnings of `tailor check` are errors (exit 11)")
    parser.add_argument("--timeout", type=positive_seconds, default=None, metavar="S", help="planner time limit")
    parser.add_argument("--simulate", action="store_true", help="execute greedy and refined sequences in the simulator")
    parser.add_argument("--plot", metavar="FILE.png",
                        help="draw greedy and refined trajectories side by side (simulates them); also "
                             "FILE_polar.png (the first free parameter a full-circle angle) or FILE_costs.png: "
                             "the predicted time over that parameter; and FILE_waypoint.png where two actions share a "
                             "way-point with a free angle and speed (Fig. 5.9: each action's predicted time and their "
                             "sum over both); every file written is named")
    add_filter_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    add_risk_argument(parser)
    add_neighbourhood_argument(parser)
    add_objective_arguments(parser)


def _fmt_param(p) -> str:
    if p.free:
        return f"{p.name}=[{p.low:.3g}, {p.high:.3g}]"
    return f"{p.name}={p.value:.3f}"


def _execution_json(outcome, success_models=None) -> dict:
    refined, simulated = outcome.refined, outcome.simulated
    success = predicted_success(refined.sequence, success_models) if success_models else None
    actions = []
    for k, (action, predicted) in enumerate(zip(refined.sequence.actions, refined.predicted)):
        entry = {"step": action.step, "pddl": action.pddl, "action": action.action,
                 "params": {p.name: p.value for p in action.params}, "predicted": round(predicted, 4)}
        if action.guard:  # Alg. 6: the success model it must satisfy, and whether it does at the chosen values
            entry.update(guard=action.guard, predicted_success=success[k] if success else None)
        if action.origin:  # inserted by subgoal assertion: which plan step it serves, and why
            entry["origin"] = action.origin
        if refined.measures and len(refined.measures[k]) > 1:  # every measure its model predicts (Ch. 8.1)
            entry["measures"] = {name: round(value, 6) for name, value in refined.measures[k].items()}
        if simulated is not None:
            if k < len(simulated.results):
                entry["simulated"] = round(simulated.results[k].duration, 4)
                entry["outcome"] = simulated.results[k].outcome
                entry["simulated_measures"] = {DURATION: round(simulated.results[k].duration, 6),
                                               **{name: round(value, 6)
                                                  for name, value in simulated.results[k].measures.items()}}
            else:
                entry["simulated"] = None
                entry["outcome"] = "not_started"
        actions.append(entry)
    if refined.spread is not None:  # each action's uncertainty (models.uncertainty) at the chosen values
        for entry, spread in zip(actions, refined.spread):
            entry["uncertainty"] = round(spread, 4)
    data = {"horizon": refined.horizon, "risk": refined.risk, "neighbourhood": refined.neighbourhood, "actions": actions,
            "predicted_total": round(refined.predicted_total, 4),
            "optimizers": optimizers_run(refined.windows),
            "optimization": [window_json(w) for w in refined.windows],
            "objective": refined.objective.to_json(), "limits": {b.measure: b.bound for b in refined.limits},
            "violations": [v.to_json() for v in refined.violations]}
    if _measure_names([refined]):
        data["predicted_measures_total"] = {name: round(refined.measure_total(name), 6)
                                            for name in (DURATION, *_measure_names([refined]))}
    if simulated is not None:
        data["simulated_total"] = round(simulated.duration, 4)
        data["succeeded"] = simulated.succeeded
        names = dict.fromkeys(name for r in simulated.results for name in r.measures)
        data["simulated_measures_total"] = {DURATION: round(simulated.duration, 6),
                                            **{name: round(sum(r.measures[name] for r in simulated.results
                                                               if name in r.measures), 6) for name in names}}
    return data


def _measure_names(refinements) -> list[str]:
    """The measures besides the duration that every action of every refinement's models predict, in order."""
    names = None
    for refined in refinements:
        for measures in refined.measures or ({DURATION: 0.0},):
            ordered = [name for name in measures if name != DURATION]
            names = ordered if names is None else [n for n in names if n in ordered]
    return list(names or ())


def optimizers_run(windows) -> list[str]:
    """The optimizers whose choices a refinement's windows took, in the order they first did."""
    return list(dict.fromkeys(w.method for w in windows))


def window_json(window) -> dict:
    """One window's optimization: which optimizer's choice, its cost (the worst case over a neighbourhood), and
    the certified lower bound and gap (s, and as a share of the cost) where there is one (null: unknown)."""
    gap = window.gap
    return {"method": window.method, "cost": round(window.cost, 4), "evaluations": window.evaluations,
            "seconds": window.seconds,
            "lower_bound": None if window.lower_bound is None or not math.isfinite(window.lower_bound)
            else round(window.lower_bound, 4),
            "gap": None if gap is None else round(gap, 6),
            "gap_share": None if gap is None or not math.isfinite(window.gap_share) else round(window.gap_share, 6),
            "note": window.note}


def models_read(result, meta) -> list[Path]:
    """The model files a refinement read: the duration models of its actions, the success classifiers of its
    guards, and the meta model where the filter judged with it."""
    folder = result.models_dir
    files = [folder / f"{action}.json" for action in result.models]
    files += [folder / f"{name}{COLLISION_SUFFIX}" for name in result.success_models]
    return files + ([meta_model_path(folder)] if meta is not None else [])


def result_json(result, method: str, seed: int, origin: Provenance | None = None) -> dict:
    """Schema tailor.refine/1: the plan, the free parameters with their ranges and chosen values, and the
    refined and greedy executions in the same structure; led by `origin` where given."""
    chosen = {p.id: p.value for a in result.refined.refined.sequence.actions for p in a.params}
    greedy_values = {p.id: p.value for a in result.greedy.refined.sequence.actions for p in a.params}
    data = {
        "domain": result.plan.domain, "problem": result.plan.problem, "planner": result.plan.planner,
        "optimizer": method, "horizon": result.refined.refined.horizon, "seed": seed, "models": str(result.models_dir),
        "plan": result.plan.to_json(),
        # full precision: the printed values reproduce the prediction (an optimum may lie on a split of a tree)
        "free_parameters": [{"id": p.id, "low": p.low, "high": p.high, "value": chosen[p.id],
                             "greedy": greedy_values[p.id]}
                            for p in result.sequence.free_parameters()],
    }
    if result.assertions:
        data["assertions"] = [a.to_json() for a in result.assertions]
    if result.decision is not None:  # the meta filter (Sec. 5.5.4): refined, or greedy kept
        data["filter"] = result.decision.to_json()
    data["refined"] = _execution_json(result.refined, result.success_models)
    data["greedy"] = _execution_json(result.greedy, result.success_models)
    names = _measure_names([result.refined.refined, result.greedy.refined])
    limited = [b.measure for b in result.refined.refined.limits]
    data["measure_units"] = {name: _unit(result, name) for name in [DURATION, *dict.fromkeys([*names, *limited])]}
    return versioned("refine", data, origin)


def _unit(result, measure: str) -> str:
    return "s" if measure == DURATION else result.binding.entry.quantity(measure).unit


def _gain(refined: float, greedy: float) -> str:
    """1 - refined / greedy as a percentage; "-" where greedy takes no time (nothing to compare with)."""
    return f"{100 * (1 - refined / greedy):.1f}%" if greedy > 0 else "-"


def _print_text(result) -> None:
    """The plan, the instantiated sequence, the free parameters chosen and the durations, as a table; the header
    of the refined column names the optimizers whose choices it took (not the one asked for: auto is none)."""
    out = sys.stdout.write
    plan, decision = result.plan, result.decision
    outcomes = {"greedy": result.greedy, "refined": result.refined}
    out(f"Plan ({plan.planner}) for {plan.domain}/{plan.problem}:\n{render_text(plan)}\n")
    asserted = " and subgoals asserted" if result.assertions else ""
    out(f"Instantiated action sequence{asserted} (free parameters as [low, high]):\n")
    for a in result.sequence.actions:
        out(f"  {a.step} {a.action:<13} {a.pddl}\n      {' '.join(_fmt_param(p) for p in a.params)}\n")
        if a.guard:
            out(f"      guarded by success model {a.guard} (Alg. 6: invalid where it predicts failure)\n")
        if a.origin:
            out(f"      inserted: {a.origin}\n")
    for check in result.assertions:
        out(f"Subgoal assertion, step {check.step} {check.pddl}: {check.reason()}\n")
    if decision is not None:
        out(f"Meta filter (Sec. 5.5.4): {decision.reason}\n")
    free = result.sequence.free_parameters()
    risk, around = outcomes["refined"].refined.risk, outcomes["refined"].refined.neighbourhood
    ran = "+".join(optimizers_run(outcomes["refined"].refined.windows)) or "nothing free"
    names = [("greedy", "greedy (h=1)"),
             ("refined", f"refined (h={outcomes['refined'].refined.horizon}, {ran}"
                         + (f", risk {risk:g}" if risk else "") + (f", neighbourhood {around:g}" if around else "")
                         + ")")]
    names = [(k, label) for k, label in names if k in outcomes]
    width = max(28, *(len(label) + 2 for _, label in names))  # a column per execution, its label fits
    if free:
        out("\nFree parameters chosen:\n")
        out(f"  {'parameter':<16}" + "".join(f"{label:>{width}}" for _, label in names) + "\n")
        for p in free:
            angle = result.binding.entry.quantity(p.id).angle  # declared by the simulator, not guessed from a name
            cells = []
            for key, _ in names:
                value = next(q.value for a in outcomes[key].refined.sequence.actions for q in a.params if q.id == p.id)
                value = round(value, 3) + 0.0  # (a value that rounds to zero prints as 0, never as -0)
                cells.append(f"{value:.3f} ({math.degrees(value):.0f}°)" if angle else f"{value:.3f}")
            out(f"  {p.id:<16}" + "".join(f"{c:>{width}}" for c in cells) + "\n")
    simulate = all(outcomes[k].simulated is not None for k, _ in names)

    def duration_cell(o, k: int) -> str:
        cell = f"{o.refined.predicted[k]:.2f}"
        if simulate:
            res = o.simulated.results
            cell += f" / {res[k].duration:.2f}" if k < len(res) else " / -"
            if k < len(res) and res[k].outcome != "success":
                cell += f" ({res[k].outcome})"
        return cell

    _table(result, outcomes, names, width, "Durations (s)", simulate, duration_cell,
           lambda o: f"{o.refined.predicted_total:.2f}" + (f" / {o.simulated.duration:.2f}" if simulate else ""))
    if len(names) == 2:
        g, r = outcomes["greedy"], outcomes["refined"]
        line = f"\nImprovement of refined over greedy: predicted {_gain(r.refined.predicted_total, g.refined.predicted_total)}"
        if simulate and g.simulated.succeeded and r.simulated.succeeded:
            line += f", simulated {_gain(r.simulated.duration, g.simulated.duration)}"
        out(line + "\n")
    _print_measures(result, names, width, simulate)
    unit = " s" if outcomes["refined"].refined.objective.plain else ""  # (a weighted sum has no one unit)
    for w in outcomes["refined"].refined.windows:
        note = f" ({w.note})" if w.note else ""
        gap = "" if w.gap is None else f", gap {w.gap:.3g}{unit} ({100 * w.gap_share:.2g}%)"
        out(f"Optimizer: {w.method}, {1000 * w.seconds:.1f} ms, {w.evaluations} evaluations{gap}{note}\n")


def _print_measures(result, names, width: int, simulate: bool) -> None:
    """The objective and limits where they are not the plain duration, and a table per further measure the
    models predict (predicted / simulated per action and in total, as the durations), then every limit no
    choice kept."""
    out = sys.stdout.write
    outcomes = {"greedy": result.greedy, "refined": result.refined}
    refined = outcomes["refined"].refined
    if not refined.objective.plain or refined.limits:
        limits = ", ".join(f"{b.measure} <= {b.bound:g} {_unit(result, b.measure)}".rstrip() for b in refined.limits)
        out(f"\nObjective: {refined.objective.text()}" + (f"; every action's predicted {limits}" if limits else "")
            + "\n")
    n = len(result.sequence.actions)
    for measure in _measure_names([outcomes[key].refined for key, _ in names]):
        unit = _unit(result, measure)

        def measure_cell(o, k: int, measure=measure) -> str:
            res = o.simulated.results if simulate else ()
            return f"{o.refined.measures[k][measure]:.4g}" + (
                "" if not simulate else f" / {res[k].measures[measure]:.4g}"
                if k < len(res) and measure in res[k].measures else " / -")

        def measure_total(o, measure=measure) -> str:
            done = [r.measures[measure] for r in o.simulated.results if measure in r.measures] if simulate else []
            return f"{o.refined.measure_total(measure):.4g}" + (
                "" if not simulate else f" / {sum(done):.4g}" if len(done) == n else " / -")

        _table(result, outcomes, names, width, measure.capitalize() + (f" ({unit})" if unit else ""), simulate,
               measure_cell, measure_total)
    for key, label in names:
        for violation in outcomes[key].refined.violations:
            out(f"Limit not kept ({label}): {violation.reason()}\n")


def _table(result, outcomes, names, width: int, title: str, simulate: bool, cell, total) -> None:
    """One value per action and execution (`cell(outcome, k)`), predicted (/ simulated), and their totals."""
    out = sys.stdout.write
    out(f"\n{title}, predicted" + (" / simulated" if simulate else "") + ":\n")
    out(f"  {'action':<24}" + "".join(f"{label:>{width}}" for _, label in names) + "\n")
    for k, action in enumerate(result.sequence.actions):
        out(f"  {str(action.step) + ' ' + action.action:<24}"
            + "".join(f"{cell(outcomes[key], k):>{width}}" for key, _ in names) + "\n")
    out(f"  {'total':<24}" + "".join(f"{total(outcomes[key]):>{width}}" for key, _ in names) + "\n")


def _check_limits(result) -> None:
    """A TailorError (status 9, after the output) naming the first limit the refined sequence breaks."""
    violations = result.refined.refined.violations
    if violations:
        more = f" (and {len(violations) - 1} more, listed above)" if len(violations) > 1 else ""
        raise TailorError(f"limit not kept: {violations[0].reason()}{more}")


NOTHING_TO_REFINE = "the goal holds in the initial state: the plan is empty, nothing to refine or simulate"


def _nothing_to_refine(result, args: argparse.Namespace, origin: Provenance) -> int:
    """An empty plan is a success in every mode: it is printed, with zero durations (and, asked to simulate,
    a trivially successful execution); no plot is drawn, since there is no trajectory."""
    plan = result.plan
    if args.plot:
        logging.getLogger(__name__).warning("%s not written: %s", args.plot, NOTHING_TO_REFINE)
    if not args.json:
        sys.stdout.write(f"Plan ({plan.planner}) for {plan.domain}/{plan.problem}:\n{render_text(plan)}\n"
                         f"Nothing to refine: {NOTHING_TO_REFINE}.\n")
        return 0
    objective = (args.objective or result.binding.objective).to_json()
    execution = {"horizon": args.horizon, "risk": args.risk or 0.0, "neighbourhood": args.neighbourhood or 0.0,
                 "actions": [], "predicted_total": 0.0, "optimization": [], "objective": objective,
                 "limits": {b.measure: b.bound for b in bounds_of(args.limits)}, "violations": []}
    if args.simulate or args.plot:
        execution.update(simulated_total=0.0, succeeded=True)
    data = {"domain": plan.domain, "problem": plan.problem, "planner": plan.planner, "optimizer": args.optimizer,
            "horizon": args.horizon, "seed": args.seed, "models": str(result.models_dir), "plan": plan.to_json(),
            "free_parameters": [], "refined": execution,
            "greedy": {**execution, "horizon": 1, "risk": 0.0, "neighbourhood": 0.0}, "note": NOTHING_TO_REFINE}
    sys.stdout.write(json.dumps(versioned("refine", data, origin), indent=1, allow_nan=False) + "\n")
    return 0


def run(args: argparse.Namespace) -> int:
    """Read the task once, run the driver, format its result (text or JSON) and draw it (--plot)."""
    if args.plot:  # before planning and refining: a plot that cannot be written must not cost their time
        for path in (args.plot, *cost_plot_names(args.plot)):  # (which is drawn is known once instantiated)
            check_output_file(path, ".png")
    try:
        limits = bounds_of(args.limits)
    except ObjectiveSyntaxError as exc:
        raise UsageError(f"--max: {exc}") from None
    inputs = pipeline.read_task(pipeline.resolve_task(args.domain, args.problem, args.belief), args.models)
    for option, objective, bounds in (("--objective", args.objective, ()), ("--max", None, limits)):
        wrong = pipeline.unknown_measure(inputs.binding, objective, bounds)  # before planning: a typo costs nothing
        if wrong is not None:
            raise UsageError(f"{option}: {wrong}")
    use_filter = inputs.binding.refinement.filter if args.filter is None else args.filter
    meta = load_meta_model(inputs.models.path) if use_filter else None  # a bad one fails before planning
    options = pipeline.Options(horizon=args.horizon, optimizer=args.optimizer, seed=args.seed, risk=args.risk,
                               neighbourhood=args.neighbourhood, filter=args.filter, zero=None if args.plot else False,
                               simulate=args.simulate or bool(args.plot), planner=args.planner, timeout=args.timeout,
                               strict=args.strict, objective=args.objective, limits=limits)
    started = time.perf_counter()
    with showing_progress(getattr(args, "progress", True)):  # the genetic algorithm takes seconds per window
        given = plan_from_ipc(inputs.pddl, args.plan) if args.plan else None
        result = pipeline.run(inputs, options, plan=given, meta=meta)
    logging.getLogger(__name__).debug("planned and refined greedy and with h=%d in %.2f s", args.horizon,
                                      time.perf_counter() - started)
    origin = provenance(getattr(args, "argv", None), {"seed": args.seed}, models_read(result, meta))
    if result.empty:
        return _nothing_to_refine(result, args, origin)
    announce_models("refine", inputs.models)  # once the models have made their predictions: an error stays one line
    written = ()
    if args.plot:
        executions = {"greedy": result.greedy, "refined": result.refined}
        if result.zero is not None:
            executions = {"zero": result.zero, **executions}
        written = draw_refinement(args.plot, result, executions, inputs.binding.entry.views)
    if args.json:
        sys.stdout.write(json_text(result_json(result, args.optimizer, args.seed, origin)) + "\n")
        if written:  # stdout holds the JSON only
            logging.getLogger(__name__).info("wrote %s", ", ".join(str(path) for path in written))
    else:
        _print_text(result)
        sys.stdout.write("".join(f"Wrote {path}\n" for path in written))
    _check_limits(result)
    return 0
