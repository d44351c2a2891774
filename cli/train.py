"""`tailor train DOMAIN`: learn the domain's action models from simulated experience (Chapter 4)."""

from __future__ import annotations

import argparse
import contextlib
import functools
import logging
import sys
from pathlib import Path

from tailor.cli.arguments import (MAX_EPISODES, add_backend_arguments, backend_session, seed, whole_number,
                                            worker_count)

MIN_EPISODES = 8  # a quarter of the episodes is the test set

DESCRIPTION = ("gather experience in the simulator and learn the action models (durations, success classifiers, and the "
               "further measures the binding's [training.models.ACTION] measures declare, e.g. energy and end error). "
               "Prints a short summary and names every file written: the models (DIR/models/*.json) "
               "and, in DIR/training/, report.html (tables, learning curves, pictures and the rules in one page), "
               "report.txt (tables and the full rules) and report.json; a warning on stderr where the run is too "
               "small to trust.")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("domain", help="bundled domain name, a domain folder, or its domain.pddl")
    parser.add_argument("--episodes", type=whole_number(MIN_EPISODES, MAX_EPISODES), default=None, metavar="N",
                        help="episodes gathered per scenario, at least 8: a quarter of them is the test set "
                             "(default: the domain's [training] episodes, and a model's own episodes where its "
                             "[training.models.ACTION] names them)")
    parser.add_argument("--fresh-episodes", type=whole_number(1, MAX_EPISODES), default=None, metavar="M",
                        help="fresh episodes each success classifier is evaluated on (default: the domain's)")
    parser.add_argument("--seed", type=seed, default=0, help="seed of experience and training (default 0)")
    parser.add_argument("--jobs", type=worker_count, default=1, metavar="J",
                        help="simulator worker processes (default 1; at most the number of CPUs)")
    parser.add_argument("--out", type=Path, default=None, metavar="DIR",
                        help="write DIR/models/*.json and DIR/training/ (default: the user's data folder, "
                             "<user data>/tailor/<domain>; the bundled models are never overwritten)")
    parser.add_argument("--n-i", type=_positive_ints, default=None, metavar="LIST",
                        help="candidate examples per episode n_i, comma-separated (default 1,2,3,5,10,20,30,50)")
    parser.add_argument("--only", type=_names, default=None, metavar="ACTIONS",
                        help="learn only these models of the recipe (comma-separated actions), e.g. a model new to "
                             "the domain, leaving the others alone (use with --out: the report covers only them)")
    parser.add_argument("--json", action="store_true", help="print the report as JSON on stdout")
    parser.add_argument("--log", type=Path, nargs="+", default=None, metavar="FILE",
                        help="learn the duration models from recorded executions instead of the simulator: logs in "
                             "the format tailor.action_log/1 (CSV, or Parquet with pip install 'tailor[logs]'; see "
                             "docs/logs.md), e.g. a real robot's or `tailor gather --format csv`; every row is "
                             "checked before anything is trained (no classifiers or subgoal experience then)")
    parser.add_argument("--no-compare", dest="compare", action="store_false",
                        help="skip Fig. 4.3's comparison of feature spaces (raw, generic row, expert, auto) per "
                             "duration model")
    parser.add_argument("--black-box", action="store_true",
                        help="learn every duration model on generated features (Sec. 4.1.1), as for a robot whose "
                             "controller tailor does not know: the binding's feature spaces and the simulator's "
                             "own are neither used nor compared (success classifiers keep theirs)")
    parser.add_argument("--experience", type=Path, default=None, metavar="DIR",
                        help="keep the gathered episodes as shards in DIR and reuse the ones already there (`tailor "
                             "gather` writes them too): only missing episodes are simulated (default: OUT/experience)")
    add_backend_arguments(parser)


def _positive_ints(text: str) -> tuple[int, ...]:
    try:
        values = tuple(int(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None
    if not values or min(values) < 1:
        raise argparse.ArgumentTypeError(f"n_i candidates must be positive, got {text!r}")
    return values


def _names(text: str) -> tuple[str, ...]:
    names = tuple(part.strip() for part in text.split(",") if part.strip())
    if not names:
        raise argparse.ArgumentTypeError(f"expected comma-separated action names, got {text!r}")
    return names


def _only(recipe, actions: tuple[str, ...]):
    """The recipe cut down to the models and classifiers of `actions` (and their subgoal experience)."""
    from dataclasses import replace

    from tailor.errors import BindingError
    from tailor.refinement.binding import BINDING_FILE
    from tailor.refinement.binding_domain import did_you_mean

    known = {m.action for m in (*recipe.models, *recipe.classifiers)}
    for action in actions:
        if action not in known:
            raise BindingError(f"--only {action}: the [training] table learns no model of it (it learns "
                               f"{', '.join(sorted(known))}){did_you_mean(action, known)}",
                               file=str(recipe.domain_dir / BINDING_FILE))
    return replace(recipe, models=tuple(m for m in recipe.models if m.action in actions),
                   classifiers=tuple(c for c in recipe.classifiers if c.action in actions),
                   subgoal_experience=tuple(c for c in recipe.subgoal_experience if c.action in actions))


def _companions(recipe, out: Path) -> dict:
    """With --only: the domain's other action models, which the subgoal experience of the models learned may
    refine with (from OUT's models where it holds them, else those refine would read; loaded before any work)."""
    if not recipe.subgoal_experience:
        return {}
    from tailor.refinement.model_store import MODELS, resolve_models
    from tailor.refinement.models.action_models import load_action_models

    learned = {m.action for m in recipe.models}
    out_models = Path(out) / MODELS
    folder = out_models if any(out_models.glob("*.json")) else resolve_models(recipe.domain_dir).path
    return {action: model for action, model in load_action_models(folder).items() if action not in learned}


def run(args: argparse.Namespace) -> int:
    from tailor.planner_bridge import resolve_domain_dir
    from tailor.refinement.binding import BINDING_FILE
    from tailor.errors import BindingError
    from tailor.refinement.learning.duration_protocol import N_I_CANDIDATES
    from tailor.refinement.learning.recipe import load_recipe
    from tailor.refinement.learning.training import RenameHold, train_domain
    from tailor.outputs import check_output_dir, provenance
    from tailor.sims.shards import experience_lock, stored_gather

    recipe = load_recipe(resolve_domain_dir(args.domain))
    if args.only:
        recipe = _only(recipe, args.only)
    if args.black_box:
        from tailor.refinement.learning.recipe import black_box

        recipe = black_box(recipe)
    episodes = recipe.episodes if args.episodes is None else args.episodes
    if episodes < MIN_EPISODES:  # the domain's own [training] episodes
        raise BindingError(f"[training] episodes must be at least {MIN_EPISODES} (a quarter of them is the test "
                           f"set), got {episodes}", file=str(recipe.domain_dir / BINDING_FILE))
    from tailor.refinement.model_store import default_training_out

    out = default_training_out(recipe.domain_dir) if args.out is None else args.out
    if args.only and args.out is None:  # refine would read this folder alone, before the bundled models
        logging.getLogger(__name__).warning(
            "--only without --out writes only %s into %s, which `tailor refine` then reads before the bundled "
            "models: give --out DIR to keep them apart", ", ".join(args.only), out / "models")
    check_output_dir(out)  # before gathering anything: minutes of work must not end in an unwritable folder
    experience = out / "experience" if args.experience is None else args.experience
    check_output_dir(experience)
    recorded = None
    if args.log:
        from tailor.refinement.learning.logs import read_logs
        from tailor.sims import registry

        recorded = read_logs(args.log, registry.get(recipe.simulator), recipe.duration_actions)
    companions = _companions(recipe, out) if args.only and not args.log else {}
    origin = provenance(getattr(args, "argv", None), {"seed": args.seed},
                        [model.source for model in companions.values()])  # the model files read
    gathering = experience_lock(experience) if recorded is None else contextlib.nullcontext()
    # Once training renames its first finished file into place the run is done: Ctrl-C and SIGTERM are dropped
    # from then until the workers are stopped (the session's end), and the run ends with 0 (docs/exit-statuses.md)
    hold, report = RenameHold(), None
    try:
        with hold, backend_session(args), gathering:  # one run at a time gathers into an experience folder
            report = train_domain(recipe, episodes, args.seed, out, jobs=args.jobs,
                                  fresh_episodes=args.fresh_episodes, n_i_candidates=args.n_i or N_I_CANDIDATES,
                                  progress=getattr(args, "progress", True), own_episodes=args.episodes is None,
                                  gather=functools.partial(stored_gather, experience), companions=companions,
                                  compare=args.compare, recorded=recorded, provenance=origin, hold=hold)
        _print_report(args, report, out)
    except KeyboardInterrupt:
        if not hold.begun and report is None:  # interrupted before any file was put in place
            raise
        # the models are written and complete (printing the report stays interruptible, should its reader stall)
        print(f"tailor train: interrupted while printing the report; the models in {out / 'models'} are complete",
              file=sys.stderr)
    return 0


def _print_report(args: argparse.Namespace, report: dict, out: Path) -> None:
    """The warnings (stderr), then the report: its summary and the files written, or the report as JSON."""
    from tailor.outputs import json_text
    from tailor.refinement.learning.report import summary_lines
    from tailor.refinement.learning.training import REPORT_FILES
    from tailor.refinement.model_store import ENVIRONMENT_VARIABLE, USER_DATA

    log = logging.getLogger(__name__)
    written = [Path(out) / name for name in report.get("files", ())]
    for warning in report.get("warnings", ()):  # diagnostics: stderr, also under --json (and in the reports)
        log.warning("this run is too small to trust: %s", warning)
    if args.json:
        sys.stdout.write(json_text(report) + "\n")  # the report, led by its own schema
        log.info("wrote %s", ", ".join(str(path) for path in written))
        return
    print("\n".join(summary_lines(report)))
    print(f"\nWrote {len(written)} files:")
    width = max((len(str(path)) for path in written), default=0)
    for path in written:
        what = REPORT_FILES.get(path.name, "the report as JSON" if path.name == "report.json" else "")
        print(f"  {str(path):<{width}}  {what}".rstrip())
    if args.out is None:  # found there before the bundled models (model_store.resolve_models)
        print(f"`tailor refine {args.domain} PROBLEM` uses them from now on (the {USER_DATA} comes before "
              f"the bundled models; --models DIR or {ENVIRONMENT_VARIABLE} choose others)")
    else:
        print(f"Use them with `tailor refine {args.domain} PROBLEM --models {out}`")
