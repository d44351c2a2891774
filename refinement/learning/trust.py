"""Whether a training run is big enough to trust: one warning per result a user should not rely on.

A run on a handful of episodes still writes models and a report full of numbers; these checks say where the
numbers are too thin to mean anything (the floors are deliberately low: a warning means "gather more", not
"could be better"). They read only the training report, so any report, also an older one, can be checked.
"""

from __future__ import annotations

MIN_TEST_EPISODES = 50  # held-out episodes behind a duration model's MAE; fewer: its standard error is large
MIN_FRESH_EPISODES = 100  # fresh episodes behind a classifier's confusion matrix
MIN_FAILURES = 10  # failing training episodes a classifier needs to learn where its action fails
CHANCE_BALANCED_ACCURACY = 0.6  # mean of the two per-class accuracies; 0.5 is what guessing achieves


def trust_warnings(report: dict) -> list[str]:
    """One line per result of `report` (a training report, schema 2 or 3) too thin to trust."""
    warnings = []
    for action, row in report.get("models", {}).items():
        warnings += _duration_warnings(action, row)
    for action, row in classifier_reports(report).items():
        warnings += _classifier_warnings(action, row)
    return warnings


def classifier_reports(report: dict) -> dict[str, dict]:
    """The success classifiers' rows by action (schema 3 `classifiers`; schema 2 had one, `collision`)."""
    if "classifiers" in report:
        return dict(report["classifiers"])
    old = report.get("collision")
    return {old["action"]: old} if old else {}


def _duration_warnings(action: str, row: dict) -> list[str]:
    out = []
    tested = row.get("test_episodes", 0)
    if tested < MIN_TEST_EPISODES:
        out.append(f"duration model of {action}: MAE measured on only {tested} held-out episodes (of "
                   f"{row['episodes']} successful): a rough estimate; gather more episodes (--episodes)")
    constant = row.get("mae_constant")
    if constant is not None and row["mae"] >= constant:
        out.append(f"duration model of {action}: MAE {row['mae']:.3f} s is no better than always predicting the "
                   f"median duration ({constant:.3f} s): it has learned nothing; gather more episodes")
    return out


def balanced_accuracy(counts: dict) -> float | None:
    """Mean of the accuracy on failing and on succeeding episodes; None where one kind is missing."""
    fail = counts["predicted_fail_observed_fail"] + counts["predicted_success_observed_fail"]
    success = counts["predicted_fail_observed_success"] + counts["predicted_success_observed_success"]
    if not fail or not success:
        return None
    return 0.5 * (counts["predicted_fail_observed_fail"] / fail + counts["predicted_success_observed_success"] / success)


def _classifier_warnings(action: str, row: dict) -> list[str]:
    out = []
    name = f"success classifier of {action}"
    failures = sum(n for outcome, n in row.get("outcomes", {}).items() if outcome != "success")
    if failures < MIN_FAILURES:
        out.append(f"{name}: learned from only {failures} failing episodes: it cannot know where the action "
                   "fails; gather more episodes")
    confusion = row["confusion"]
    fresh = confusion["episodes"]
    if fresh < MIN_FRESH_EPISODES:
        out.append(f"{name}: evaluated on only {fresh} fresh episodes: its accuracy is a rough estimate "
                   "(--fresh-episodes)")
    balanced = balanced_accuracy(confusion["counts"])
    if balanced is None:
        out.append(f"{name}: the fresh episodes hold only one outcome: its accuracy says nothing about the other")
    elif balanced <= CHANCE_BALANCED_ACCURACY:
        out.append(f"{name}: at chance level ({100 * row['accuracy']:.1f}% correct, but on failing and succeeding "
                   f"episodes {100 * balanced:.0f}% on average, where guessing gets 50%)")
    return out
