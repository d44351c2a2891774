"""`tailor refine DOMAIN PROBLEM`: plan, instantiate, refine the free parameters (Sec. 5.4), optionally simulate.

Greedy execution (h = 1) is always computed beside the requested horizon, so the gain can be read off.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
import time

from tailor.cli.arguments import (
    add_filter_arguments,
    add_models_argument,
    add_neighbourhood_argument,
    add_risk_argument,
    announce_models,
    positive_seconds,
    seed,
    whole_number,
)

HELP = "refine the free parameters of a plan for the fastest predicted execution, optionally simulate it"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from tailor.refinement.optimizers import OPTIMIZERS

    parser.add_argument("domain", metavar="DOMAIN", help="domain.pddl file, the folder holding it, or the name of a bundled domain (see `tailor domains`)")
    parser.add_argument("problem", metavar="PROBLEM", help="problem .pddl file, or the name of one of its problems")
    parser.add_argument("--optimizer", choices=sorted(OPTIMIZERS), default="analytic",
                        help="analytic model-tree minimization (falls back to ga where it does not apply), "
                             "genetic algorithm, or random sampling (default: analytic)")
    parser.add_argument("--horizon", type=whole_number(1), default=2, metavar="H",
                        help="actions optimized together (default 2; 1 is greedy)")
    parser.add_argument("--seed", type=seed, default=0, metavar="S", help="seed of optimizer and simulator (default 0)")
    parser.add_argument("--belief", metavar="FILE", help="belief state file (default: PROBLEM's stem + .toml)")
    add_models_argument(parser)
    parser.add_argument("--planner", default="pyperplan", metavar="NAME", help="unified-planning engine, or pocl")
    parser.add_argument("--timeout", type=positive_seconds, default=None, metavar="S", help="planner time limit")
    parser.add_argument("--simulate", action="store_true", help="execute greedy and refined sequences in the simulator")
    parser.add_argument("--plot", metavar="FILE.png",
                        help="draw greedy and refined trajectories side by side (simulates them); also "
                             "FILE_polar.png (the first free parameter a full-circle angle) or FILE_costs.png: "
                             "the predicted time over that parameter; every file written is named")
    add_filter_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    add_risk_argument(parser)
    add_neighbourhood_argument(parser)


def _fmt_param(p) -> str:
    if p.free:
        return f"{p.name}=[{p.low:.3g}, {p.high:.3g}]"
    return f"{p.name}={p.value:.3f}"


def _execution_json(outcome, success_models=None) -> dict:
    from tailor.refinement.refine import predicted_success

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
        if simulated is not None:
            if k < len(simulated.results):
                entry["simulated"] = round(simulated.results[k].duration, 4)
                entry["outcome"] = simulated.results[k].outcome
            else:
                entry["simulated"] = None
                entry["outcome"] = "not_started"
        actions.append(entry)
    if refined.spread is not None:  # each action's uncertainty (models.uncertainty) at the chosen values
        for entry, spread in zip(actions, refined.spread):
            entry["uncertainty"] = round(spread, 4)
    data = {"horizon": refined.horizon, "risk": refined.risk, "neighbourhood": refined.neighbourhood, "actions": actions,
            "predicted_total": round(refined.predicted_total, 4),
            "optimization": [{"method": w.method, "cost": round(w.cost, 4), "evaluations": w.evaluations,
                              "seconds": w.seconds, "note": w.note} for w in refined.windows]}
    if simulated is not None:
        data["simulated_total"] = round(simulated.duration, 4)
        data["succeeded"] = simulated.succeeded
    return data


def result_json(prepared, method: str, seed: int, outcomes: dict, decision=None) -> dict:
    """Schema tailor.refine/1: the plan, the free parameters with their ranges and chosen values, and the
    refined and greedy executions in the same structure."""
    from tailor.outputs import versioned

    refined = outcomes["refined"].refined
    chosen = {p.id: p.value for a in refined.sequence.actions for p in a.params}
    greedy = outcomes["greedy"].refined
    greedy_values = {p.id: p.value for a in greedy.sequence.actions for p in a.params}
    data = {
        "domain": prepared.plan.domain, "problem": prepared.plan.problem, "planner": prepared.plan.planner,
        "optimizer": method, "horizon": refined.horizon, "seed": seed, "models": str(prepared.task.models_dir),
        "plan": prepared.plan.to_json(),
        # full precision: the printed values reproduce the prediction (an optimum may lie on a split of a tree)
        "free_parameters": [{"id": p.id, "low": p.low, "high": p.high, "value": chosen[p.id],
                             "greedy": greedy_values[p.id]}
                            for p in prepared.sequence.free_parameters()],
    }
    if prepared.assertions:
        data["assertions"] = [a.to_json() for a in prepared.assertions]
    if decision is not None:  # the meta filter (Sec. 5.5.4): refined, or greedy kept
        data["filter"] = decision.to_json()
    data["refined"] = _execution_json(outcomes["refined"], prepared.success_models)
    data["greedy"] = _execution_json(outcomes["greedy"], prepared.success_models)
    return versioned("refine", data)


def _gain(refined: float, greedy: float) -> str:
    """1 - refined / greedy as a percentage; "-" where greedy takes no time (nothing to compare with)."""
    return f"{100 * (1 - refined / greedy):.1f}%" if greedy > 0 else "-"


def _print_text(prepared, method: str, outcomes: dict, decision=None) -> None:
    from tailor.planner_bridge import render_text

    out = sys.stdout.write
    plan = prepared.plan
    out(f"Plan ({plan.planner}) for {plan.domain}/{plan.problem}:\n{render_text(plan)}\n")
    asserted = " and subgoals asserted" if prepared.assertions else ""
    out(f"Instantiated action sequence{asserted} (free parameters as [low, high]):\n")
    for a in prepared.sequence.actions:
        out(f"  {a.step} {a.action:<13} {a.pddl}\n      {' '.join(_fmt_param(p) for p in a.params)}\n")
        if a.guard:
            out(f"      guarded by success model {a.guard} (Alg. 6: invalid where it predicts failure)\n")
        if a.origin:
            out(f"      inserted: {a.origin}\n")
    for check in prepared.assertions:
        out(f"Subgoal assertion, step {check.step} {check.pddl}: {check.reason()}\n")
    if decision is not None:
        out(f"Meta filter (Sec. 5.5.4): {decision.reason}\n")
    free = prepared.sequence.free_parameters()
    risk, around = outcomes["refined"].refined.risk, outcomes["refined"].refined.neighbourhood
    names = [("greedy", "greedy (h=1)"),
             ("refined", f"refined (h={outcomes['refined'].refined.horizon}, {method}"
                         + (f", risk {risk:g}" if risk else "") + (f", neighbourhood {around:g}" if around else "")
                         + ")")]
    names = [(k, label) for k, label in names if k in outcomes]
    width = max(28, *(len(label) + 2 for _, label in names))  # a column per execution, its label fits
    if free:
        out("\nFree parameters chosen:\n")
        out(f"  {'parameter':<16}" + "".join(f"{label:>{width}}" for _, label in names) + "\n")
        for p in free:
            cells = []
            for key, _ in names:
                value = next(q.value for a in outcomes[key].refined.sequence.actions for q in a.params if q.id == p.id)
                cells.append(f"{value:.3f} ({math.degrees(value):.0f}°)" if p.name.startswith("phi") else f"{value:.3f}")
            out(f"  {p.id:<16}" + "".join(f"{c:>{width}}" for c in cells) + "\n")
    simulate = all(outcomes[k].simulated is not None for k, _ in names)
    out("\nDurations (s), predicted" + (" / simulated" if simulate else "") + ":\n")
    out(f"  {'action':<24}" + "".join(f"{label:>{width}}" for _, label in names) + "\n")
    for k, action in enumerate(prepared.sequence.actions):
        cells = []
        for key, _ in names:
            o = outcomes[key]
            cell = f"{o.refined.predicted[k]:.2f}"
            if simulate:
                res = o.simulated.results
                cell += f" / {res[k].duration:.2f}" if k < len(res) else " / -"
                if k < len(res) and res[k].outcome != "success":
                    cell += f" ({res[k].outcome})"
            cells.append(cell)
        out(f"  {str(action.step) + ' ' + action.action:<24}" + "".join(f"{c:>{width}}" for c in cells) + "\n")
    totals = []
    for key, _ in names:
        o = outcomes[key]
        cell = f"{o.refined.predicted_total:.2f}"
        if simulate:
            cell += f" / {o.simulated.duration:.2f}"
        totals.append(cell)
    out(f"  {'total':<24}" + "".join(f"{c:>{width}}" for c in totals) + "\n")
    if len(names) == 2:
        g, r = outcomes["greedy"], outcomes["refined"]
        line = f"\nImprovement of refined over greedy: predicted {_gain(r.refined.predicted_total, g.refined.predicted_total)}"
        if simulate and g.simulated.succeeded and r.simulated.succeeded:
            line += f", simulated {_gain(r.simulated.duration, g.simulated.duration)}"
        out(line + "\n")
    for w in outcomes["refined"].refined.windows:
        note = f" ({w.note})" if w.note else ""
        out(f"Optimizer: {w.method}, {1000 * w.seconds:.1f} ms, {w.evaluations} evaluations{note}\n")


def _zero_outcome(prepared, seed: int):
    """Every free parameter zero (clipped into its range), dispatched: the baseline of Fig. 5.14."""
    from tailor.refinement.dispatch import dispatch
    from tailor.refinement.evaluation.experiments import zero_assignment
    from tailor.refinement.pipeline import Outcome
    from tailor.refinement.refine import RefinedSequence, predicted_durations

    sequence = prepared.sequence.bind(zero_assignment(prepared.sequence))
    predicted = predicted_durations(sequence, prepared.models)
    return Outcome(RefinedSequence(sequence, predicted, (), 0), dispatch(sequence, seed=seed))


NOTHING_TO_REFINE = "the goal holds in the initial state: the plan is empty, nothing to refine or simulate"


def _nothing_to_refine(prepared, args: argparse.Namespace, simulate: bool) -> int:
    """An empty plan is a success in every mode: it is printed, with zero durations (and, asked to simulate,
    a trivially successful execution); no plot is drawn, since there is no trajectory."""
    if args.plot:
        logging.getLogger(__name__).warning("%s not written: %s", args.plot, NOTHING_TO_REFINE)
    if args.json:
        execution = {"horizon": args.horizon, "risk": args.risk or 0.0, "neighbourhood": args.neighbourhood or 0.0,
                     "actions": [], "predicted_total": 0.0,
                     "optimization": []}
        if simulate:
            execution.update(simulated_total=0.0, succeeded=True)
        from tailor.outputs import versioned

        plan = prepared.plan
        data = {"domain": plan.domain, "problem": plan.problem, "planner": plan.planner, "optimizer": args.optimizer,
                "horizon": args.horizon, "seed": args.seed, "models": str(prepared.task.models_dir),
                "plan": plan.to_json(), "free_parameters": [],
                "refined": execution, "greedy": {**execution, "horizon": 1, "risk": 0.0, "neighbourhood": 0.0},
                "note": NOTHING_TO_REFINE}
        sys.stdout.write(json.dumps(versioned("refine", data), indent=1, allow_nan=False) + "\n")
    else:
        from tailor.planner_bridge import render_text

        plan = prepared.plan
        sys.stdout.write(f"Plan ({plan.planner}) for {plan.domain}/{plan.problem}:\n{render_text(plan)}\n"
                         f"Nothing to refine: {NOTHING_TO_REFINE}.\n")
    return 0


def _meta_model(args: argparse.Namespace, task, source):
    """The meta action model when the filter is on (--filter, else the binding's [evaluation] filter)."""
    use = args.filter
    if use is None:
        from tailor.refinement.evaluation.experiments import binding_filter
        from tailor.refinement.pipeline import load_binding

        use = binding_filter(load_binding(task))
    if not use:
        return None
    from tailor.refinement.models.meta_model import load_meta_model

    meta = load_meta_model(source.path)
    if meta.horizon != args.horizon and args.horizon > 1:
        logging.getLogger(__name__).warning("the meta model judges refinement with h=%d, not the h=%d asked for",
                                            meta.horizon, args.horizon)
    return meta


def run(args: argparse.Namespace) -> int:
    from tailor.refinement.pipeline import (GREEDY_HORIZON, dispatched, prepare, refine_and_dispatch, refine_prepared,
                                             resolve_task)
    from tailor.progress import showing_progress

    if args.plot:  # before planning and refining: a plot that cannot be written must not cost their time
        from tailor.outputs import check_output_file
        from tailor.refinement.refine_plots import cost_plot_names

        check_output_file(args.plot, ".png")
        for companion in cost_plot_names(args.plot):  # (which one is drawn is known once the plan is instantiated)
            check_output_file(companion, ".png")
    from dataclasses import replace

    from tailor.refinement.model_store import resolve_models

    log = logging.getLogger(__name__)
    started = time.perf_counter()
    task = resolve_task(args.domain, args.problem, args.belief)
    source = resolve_models(task.domain_dir, args.models)
    task = replace(task, models=source.path)
    meta = _meta_model(args, task, source)  # a missing or bad meta model fails before planning
    prepared = prepare(task, args.planner, args.timeout)
    log.debug("planned, instantiated and loaded the models in %.2f s", time.perf_counter() - started)
    simulate = args.simulate or bool(args.plot)
    if not prepared.sequence.actions:
        return _nothing_to_refine(prepared, args, simulate)
    if simulate:  # the scene is checked before refining: a scene object the simulator lacks fails at once
        from tailor.refinement.dispatch import check_scene

        check_scene(prepared.sequence, prepared.binding.file)
    from tailor.refinement.refine import resolve_risk

    from tailor.refinement.evaluation.experiments import binding_neighbourhood

    risk = resolve_risk(args.risk, prepared.models.values())
    neighbourhood = binding_neighbourhood(prepared.binding) if args.neighbourhood is None else args.neighbourhood
    method, seed = args.optimizer, args.seed
    decision = None
    with showing_progress(getattr(args, "progress", True)):  # the genetic algorithm takes seconds per window
        outcomes = {"greedy": refine_and_dispatch(prepared, GREEDY_HORIZON, method, seed, simulate)}
        refined = refine_prepared(prepared, args.horizon, method, seed, risk, neighbourhood)
        if meta is not None and args.horizon > GREEDY_HORIZON:  # refine, or keep greedy (Sec. 5.5.4)
            from tailor.refinement.meta_filter import decide

            decision = decide(meta, outcomes["greedy"].refined, prepared.models, refined)
        outcomes["refined"] = (dispatched(refined, seed, simulate) if decision is None or decision.refine
                               else outcomes["greedy"])
    log.debug("refined greedy and with h=%d%s in %.2f s", args.horizon,
              " and simulated both" if simulate else "", time.perf_counter() - started)
    announce_models("refine", source)  # once the models have made their predictions: an error stays one line
    if args.plot:
        from tailor.refinement.refine_plots import draw_refinement

        executions = dict(outcomes)
        if prepared.binding.evaluation.get("zero_baseline") and prepared.sequence.free_parameters():
            executions = {"zero": _zero_outcome(prepared, args.seed), **outcomes}
        written = draw_refinement(args.plot, prepared, executions, prepared.binding.entry.views)
    if args.json:
        from tailor.outputs import json_text

        sys.stdout.write(json_text(result_json(prepared, args.optimizer, args.seed, outcomes, decision)) + "\n")
        if args.plot:  # stdout holds the JSON only
            logging.getLogger(__name__).info("wrote %s", ", ".join(str(path) for path in written))
    else:
        _print_text(prepared, args.optimizer, outcomes, decision)
        if args.plot:
            sys.stdout.write("".join(f"Wrote {path}\n" for path in written))
    return 0
