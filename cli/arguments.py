"""Argument types shared by the `tailor` commands: a bad value is an argparse usage error (exit 2)."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

from tailor.sims.experience import MAX_EPISODES, MAX_SEED  # noqa: F401  (MAX_EPISODES: the commands take it from here)

MAX_SECONDS = 1e6  # about 11.6 days: longer limits (and inf) are refused; leave the option out for no limit
# episodes or situations of one command: a million simulated runs take days on one machine; larger counts are
# typing mistakes, and some commands list their seeds up front


def positive_seconds(text: str) -> float:
    """An argparse type: a finite number of seconds, positive and at most MAX_SECONDS (`inf` is refused:
    omitting the option means no limit)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of seconds: {text!r}") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be positive: {text!r}")
    if not math.isfinite(value) or value > MAX_SECONDS:
        raise argparse.ArgumentTypeError(
            f"must be at most {MAX_SECONDS:g} seconds: {text!r} (leave the option out for no limit)"
        )
    return value


def whole_number(minimum: int, maximum: int | None = None) -> Callable[[str], int]:
    """An argparse type: an integer of at least `minimum` (and at most `maximum`)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be at least {minimum}: {text!r}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(f"must be at most {maximum}: {text!r}")
        return value

    parse.__name__ = f"whole number >= {minimum}"
    return parse


def cpu_count() -> int:
    """The CPUs this process may run on (its affinity where the platform says, else os.cpu_count())."""
    import os

    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def worker_count(text: str) -> int:
    """An argparse type for --jobs: a whole number >= 1, capped at the CPU count with a note (logged: on stderr
    unless -q; more worker processes than CPUs only cost memory and start-up time)."""
    import logging

    value = whole_number(1)(text)
    cpus = cpu_count()
    if value > cpus:
        logging.getLogger(__name__).info("--jobs %d capped at %d, the number of CPUs", value, cpus)
        return cpus
    return value


worker_count.__name__ = "worker count"


def add_models_argument(parser: argparse.ArgumentParser) -> None:
    """`--models DIR`: the action models to use instead of the domain's bundled ones (see model_store)."""
    parser.add_argument("--models", metavar="DIR", default=None,
                        help="action models to use: a folder of <action>.json, or a `tailor train` output folder "
                             "(default: $TAILOR_MODELS/<domain> where it exists, else what `tailor train` wrote to the user "
                             "data folder, else the domain's bundled models)")


def add_filter_arguments(parser: argparse.ArgumentParser) -> None:
    """`--filter` / `--no-filter`: refine only where the meta action model (models/meta.json) predicts that
    refinement makes execution faster, keeping greedy elsewhere (Sec. 5.5.4); default: the binding's
    `[evaluation] filter`."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--filter", dest="filter", action="store_true", default=None,
                       help="refine only where the meta action model (models/meta.json) predicts it makes "
                            "execution faster; keep greedy elsewhere (default: the binding's [evaluation] filter)")
    group.add_argument("--no-filter", dest="filter", action="store_false",
                       help="refine every situation, whatever the binding says")


def announce_models(command: str, source) -> None:
    """The one line that says which models a command uses: a note on stderr (stdout may be JSON; -q hides it)."""
    import logging

    logging.getLogger(f"tailor.{command}").info("%s", source.describe())


def add_backend_arguments(parser: argparse.ArgumentParser) -> None:
    """--backend and --scheduler: which joblib backend runs the parallel work (tailor.sims.parallel)."""
    from tailor.sims.parallel import BACKENDS

    parser.add_argument("--backend", choices=BACKENDS, default="loky",
                        help="where the --jobs workers run: loky processes on this machine (default), a Dask "
                             "cluster (pip install 'tailor[dask]') or a Ray cluster (pip install 'tailor[ray]')")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="join the existing cluster at ADDRESS (Dask: tcp://host:8786, Ray: host:6379) and "
                             "use all its workers; without it --backend dask/ray starts a local cluster of --jobs "
                             "workers")


def backend_session(args: argparse.Namespace):
    """The backend session the parsed --backend / --scheduler / --jobs ask for (a context manager)."""
    from tailor.sims.parallel import backend_session as session

    return session(args.backend, args.jobs, args.scheduler)


def add_risk_argument(parser: argparse.ArgumentParser) -> None:
    """--risk LAMBDA: the refined sequence minimizes expected duration + LAMBDA * uncertainty (greedy stays plain)."""
    from tailor.refinement.refine import DEFAULT_RISK

    parser.add_argument("--risk", type=risk_lambda, default=None, metavar="LAMBDA",
                        help="risk-aware refinement: minimize the predicted duration plus LAMBDA times the models' "
                             "uncertainty (held-out error of each leaf), summed over the horizon; the greedy "
                             f"baseline stays plain (default {DEFAULT_RISK:g} where the models store their "
                             "uncertainty, else 0; 0 is plain refinement)")


def add_neighbourhood_argument(parser: argparse.ArgumentParser) -> None:
    """--neighbourhood SHARE: the refined sequence minimizes the worst predicted time within SHARE of each free
    range around a choice (greedy stays plain)."""
    parser.add_argument("--neighbourhood", type=neighbourhood_share, default=None, metavar="SHARE",
                        help="minimize the worst predicted duration within SHARE of each free parameter's range "
                             "around a choice (the size of the execution noise), so refinement does not choose a "
                             "dip of the models narrower than the robot can hit; the greedy baseline stays plain "
                             "(default: the binding's [evaluation] neighbourhood, else 0)")


def number(text: str) -> float:
    """The float `text` spells, or the argparse error saying it is not a number (the number types build on it)."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None


def neighbourhood_share(text: str) -> float:
    """A number in [0, 0.5) (refine.is_neighbourhood)."""
    from tailor.refinement.refine import is_neighbourhood

    value = number(text)
    if not is_neighbourhood(value):
        raise argparse.ArgumentTypeError(f"must be a share of each free range in [0, 0.5), not {text}")
    return value


def risk_lambda(text: str) -> float:
    """A number from 0 to refine.MAX_RISK."""
    from tailor.refinement.refine import MAX_RISK

    value = number(text)
    if not 0.0 <= value <= MAX_RISK:
        raise argparse.ArgumentTypeError(f"must be a number from 0 to {MAX_RISK:g}, not {text}")
    return value


def add_objective_arguments(parser: argparse.ArgumentParser) -> None:
    """--objective EXPR and --max MEASURE=BOUND (repeatable): what refinement minimizes and keeps within bounds
    (refinement.objective_grammar); a malformed one is a usage error naming the column."""
    parser.add_argument("--objective", type=objective_text, default=None, metavar="EXPR",
                        help="minimize a weighted sum of the actions' predicted measures instead of their duration, "
                             "e.g. \"duration + 0.3*energy\": terms MEASURE, NUMBER*MEASURE or MEASURE*NUMBER joined "
                             "by +, weights >= 0, each measure one the action models predict (their recipe's "
                             "measures; default: the binding's [objective], else duration); greedy minimizes the "
                             "same")
    add_limit_argument(parser, "keep every action's predicted MEASURE at most BOUND (its unit), e.g. error=0.05: "
                               "a choice that breaks it is not taken; where none keeps it, the output says which "
                               "step and the command ends with status 9 (repeatable, one bound per measure)")


def add_limit_argument(parser: argparse.ArgumentParser, help: str) -> None:
    """--max MEASURE=BOUND (repeatable) into `args.limits`."""
    parser.add_argument("--max", type=measure_limit, action="append", default=[], metavar="MEASURE=BOUND",
                        dest="limits", help=help)


def _grammar_type(parse_name: str, name: str, what: str):
    """An argparse type parsing with refinement.objective_grammar's `parse_name` (imported when first used): its
    syntax error a usage error naming the column."""

    def parse(text: str):
        from tailor.refinement import objective_grammar

        try:
            return getattr(objective_grammar, parse_name)(text)
        except objective_grammar.ObjectiveSyntaxError as exc:
            raise argparse.ArgumentTypeError(f"{text!r}: {exc}") from None

    parse.__name__, parse.__doc__ = name, f"An argparse type: {what} (refinement.objective_grammar)."
    return parse


objective_text = _grammar_type("parse_objective", "objective", "an objective, e.g. duration + 0.3*energy")
measure_limit = _grammar_type("parse_bound", "limit", "a limit MEASURE=BOUND")


seed = whole_number(0, MAX_SEED)  # an argparse type: numpy's and the simulators' generators take no negative seed
seed.__name__ = "seed"
