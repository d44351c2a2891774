"""`tailor coordinate DOMAIN`: implicit coordination of a robot team with learned action models (Ch. 7).

Runs the dynamic and the static experiment of Sec. 7.4 on the team scene of the domain's simulator and prints
Table 7.1 (Q1-Q3), agreement as estimation noise grows (Q4, Fig. 7.9), the decision tree that predicts
coordination failure (Q5, Fig. 7.10) and coordination success over communication quality and field of view for
three strategies (Q6, Fig. 7.12); `--plot DIR` draws Figs. 7.9-7.12.
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

from tailor.cli.arguments import (MAX_EPISODES, add_models_argument, announce_models, seed, whole_number,
                                            worker_count)

DEFAULT_EPISODES = 200
MAX_ROBOTS = 8
MAX_REPEATS = 31


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("domain", metavar="DOMAIN", help="bundled domain name, a domain folder, or its domain.pddl")
    parser.add_argument("--robots", type=whole_number(2, MAX_ROBOTS), default=3, metavar="N",
                        help=f"robots in the team (2-{MAX_ROBOTS}, default 3)")
    parser.add_argument("--heterogeneous", action="store_true",
                        help="one robot of the team is of the simulator's other kind, with its own action model")
    parser.add_argument("--episodes", type=whole_number(1, MAX_EPISODES), default=DEFAULT_EPISODES, metavar="N",
                        help=f"dynamic episodes (30 s each) and static situations (default {DEFAULT_EPISODES})")
    parser.add_argument("--seed", type=seed, default=0, metavar="S", help="seed of situations, noise and channel")
    parser.add_argument("--repeats", type=whole_number(1, MAX_REPEATS), default=1, metavar="K",
                        help="static: every approach again under K other noise seeds (default 1); with K >= 2 the "
                             "oracle of the expected times (the mean of the other runs) shows the best any "
                             f"predictor can do (at most {MAX_REPEATS})")
    parser.add_argument("--jobs", type=worker_count, default=1, metavar="J",
                        help="worker processes (default 1; at most the number of CPUs)")
    add_models_argument(parser)
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    parser.add_argument("--plot", metavar="DIR", default=None, help="draw Figs. 7.9-7.12 as PNG files in DIR")


def _scene(binding):
    from tailor.errors import BindingError
    from tailor.sims.team import TeamScene

    scene = binding.entry.team
    if scene is None or not isinstance(scene, TeamScene):
        raise BindingError(f"simulator {binding.simulator!r} has no team scene: it cannot run coordination "
                           "experiments", file=binding.file)
    return scene


def _load_models(models_dir, scene, kinds):
    from tailor.refinement.models.action_models import load_action_models

    actions = tuple(dict.fromkeys(scene.kinds[kind] for kind in kinds))
    return load_action_models(models_dir, actions)


def run(args: argparse.Namespace) -> int:
    from tailor.planner_bridge import resolve_domain_dir
    from tailor.refinement.binding import load_domain_binding
    from tailor.refinement.evaluation.coordination import Predictor
    from tailor.refinement.evaluation.coordination_experiments import (
        Setup,
        dynamic_episode,
        example,
        static_situation,
        summarize_dynamic,
        summarize_static,
    )
    from tailor.outputs import check_output_dir
    from tailor.sims.parallel import run_in_workers

    started = time.perf_counter()
    domain_dir = resolve_domain_dir(args.domain)
    binding = load_domain_binding(domain_dir)
    scene = _scene(binding)
    if args.plot is not None:  # the folder and each picture in it, before minutes of work
        from tailor.refinement.evaluation.coordination_plots import FILES
        from tailor.outputs import check_output_file

        check_output_dir(args.plot)
        for name in FILES:
            check_output_file(Path(args.plot) / name, ".png")
    kinds = scene.team(args.robots, args.heterogeneous)
    from tailor.refinement.model_store import resolve_models

    source = resolve_models(domain_dir, args.models)
    predictor = Predictor(scene, _load_models(source.path, scene, kinds))
    announce_models("coordinate", source)
    setup = Setup(kinds, args.seed, repeats=args.repeats)
    progress = getattr(args, "progress", True)
    static_rows = run_in_workers(static_situation, [(scene, predictor, setup, i) for i in range(args.episodes)],
                                 args.jobs, "static situations", progress, unit="sit")
    dynamic_rows = run_in_workers(dynamic_episode, [(scene, predictor, setup, i) for i in range(args.episodes)],
                                  args.jobs, "dynamic episodes", progress, unit="sit")
    static = summarize_static(static_rows)
    dynamic = summarize_dynamic(dynamic_rows, len(kinds), args.seed)
    failure = dynamic.pop("_failure")
    report = {
        "domain": binding.domain or domain_dir.name, "simulator": binding.simulator, "seed": args.seed,
        "team": list(kinds), "heterogeneous": args.heterogeneous, "episodes": args.episodes,
        "strategy": "shared",
        "agreement": dynamic["agreement"],
        "chose_quickest": static["chose_quickest"],
        "chose_quickest_distance": static["chose_quickest_distance"],
        "static": static,
        "dynamic": dynamic,
        "example": example(scene, predictor, failure),
    }
    if args.plot is not None:
        from tailor.refinement.evaluation.coordination_plots import draw_all

        written = draw_all(report, scene.bounds, args.plot)
    if args.json:
        from tailor.outputs import json_text, model_files, provenance, versioned

        origin = provenance(getattr(args, "argv", None), {"seed": args.seed}, model_files(source.path))
        sys.stdout.write(json_text(versioned("coordinate", {**report, "models": str(source.path)}, origin)) + "\n")
    else:
        _print_text(report)
    log = logging.getLogger(__name__)
    if args.plot is not None:  # (stdout holds the JSON only: the files on stderr)
        if args.json:
            log.info("wrote %s", ", ".join(str(path) for path in written))
        else:
            sys.stdout.write("".join(f"Wrote {path}\n" for path in written))
    log.info("took %.0f s", time.perf_counter() - started)
    return 0


def _pct(value) -> str:
    return "   -" if value is None else f"{100 * value:5.1f}%"


def _print_text(report: dict) -> None:
    out = sys.stdout.write
    s, d = report["static"], report["dynamic"]
    out(f"Team of {len(report['team'])} ({', '.join(report['team'])}) in simulator {report['simulator']}, "
        f"seed {report['seed']}: {d['episodes']} dynamic episodes ({d['ticks']} decisions of each robot), "
        f"{s['situations']} static situations ({s['approach_failures']} of {s['decisions']} approaches failed; "
        f"no robot knew the target in {s['target_unknown']})\n\n")
    out("Table 7.1, implicit coordination with shared belief   action model   distance\n")
    out(f"  Q1 chose the same robot (dynamic)                   {_pct(d['strategies']['shared']['agreement'])}"
        f"        {_pct(d['strategies']['distance']['agreement'])}\n")
    out(f"     chose the same robot (static)                    {_pct(s['agreement'])}"
        f"        {_pct(s['agreement_distance'])}\n")
    out(f"  Q2/Q3 chose the quickest robot (static)             {_pct(s['chose_quickest'])}"
        f"        {_pct(s['chose_quickest_distance'])}\n")
    out(f"     ... where some robot knew the target             {_pct(s['chose_quickest_target_known'])}\n")
    out(f"     ... from the true states (the models alone)      {_pct(s['chose_quickest_true_states'])}\n")
    out(f"     the same robot is quickest under other noise     {_pct(s['quickest_repeatable'])}\n")
    if s["repeats"] >= 2:
        rows = ((f"     ... scored on all {s['repeats'] + 1} runs of each approach", s["chose_quickest_every_run"]),
                ("     an oracle of the expected times (true states)", s["chose_quickest_oracle"]),
                ("     ... fed the team's belief instead", s["chose_quickest_oracle_belief"]))
        for label, value in rows:
            out(f"{label:<54}{_pct(value)}\n")
    out(f"  predicted vs measured approach time: MAE {s['prediction_mae']:.2f} s (mean {s['mean_time']:.2f} s)\n"
        if s["prediction_mae"] is not None else "")
    out("\nQ1 by strategy (dynamic): agreement / exactly one robot goes\n")
    for name, row in d["strategies"].items():
        out(f"  {name:<10} {_pct(row['agreement'])} / {_pct(row['success'])}\n")
    robots = len(report["team"])
    out("\nQ4 shared belief with noise added to teammate estimates (Fig. 7.9): share of decisions where "
        + ", ".join(str(k) for k in range(robots + 1)) + " robots go\n")
    for row in d["noise"]:
        out(f"  sigma {row['sigma']:4.2f} m  " + " ".join(_pct(v) for v in row["going_shares"]) + "\n")
    tree = d["failure_tree"]
    if tree is not None:
        out(f"\nQ5 decision tree predicting coordination failure (Fig. 7.10) of strategy {tree['strategy']} with a "
            f"{tree['field_of_view']:.0f}° field of view and {100 * tree['communication']:.0f}% communication "
            f"(trained on {tree['train_ticks']} decisions, tested on {tree['test_ticks']}; failures: "
            f"{_pct(tree['failure_share']).strip()})\n")
        for line in tree["rules"]:
            out(f"  {line}\n")
        out(f"  accuracy {_pct(tree['accuracy']).strip()} (always 'success': {_pct(tree['majority_accuracy']).strip()}; "
            f"balanced {_pct(tree['balanced_accuracy']).strip()}); "
            f"failures predicted {_pct(tree['failures_predicted']).strip()}, successes "
            f"{_pct(tree['successes_predicted']).strip()}\n")
    grid = d["communication_fov"]
    out("\nQ6 coordination success (exactly one robot goes), communication quality x field of view (Fig. 7.12)\n")
    for name, values in grid["success"].items():
        out(f"  {name:<10} " + " ".join(f"{f:>6.0f}°" for f in grid["field_of_view"]) + "\n")
        for quality, row in zip(grid["communication"], values):
            out(f"  {100 * quality:>5.0f}%    " + " ".join(_pct(v) for v in row) + "\n")
