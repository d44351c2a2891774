"""Implicit coordination with learned action models (Ch. 7): which robot of a team should go for the target?

Every robot decides at every tick (10 Hz), on its own belief, that the robot predicted to be quickest should
go (the joint utility model, Sec. 7.2); the utility is the time the robot's learned approach action model
predicts. The strategies differ in where each robot gets the predicted times from:

- explicit (Fig. 7.3): each robot predicts its own time and sends it; the others use what arrived;
- implicit (Fig. 7.4): perspective taking without communication: a robot predicts every teammate's time
  itself, with the teammate's action model, from its own estimates of the teammates' states (perceived in
  its field of view) and of the target;
- shared (Fig. 7.5): perspective taking on a shared belief: a teammate's state is the more certain of what
  the robot perceives and what the teammate last communicated (its own state estimate, time-stamped): the
  message while it is fresh, the perception where it is not or where none arrives; the target is fused from
  the robot's own observation and the ones its teammates communicated;
- distance: the shared belief's states, but the nearest robot goes (the baseline of Q3).

An estimate is weighed by its uncertainty: its noise grown with its age (a teammate may have driven on), and
forgotten after a while (Perception.memory, .target_memory). Why a teammate's state is chosen, not fused: a
message is common knowledge (every teammate holds the same one), a perception is private; fusing a little of
the private perception into everyone's estimate of a teammate makes their predicted times differ just where
two robots are nearly as quick, and the team disagrees there (measured with `tailor coordinate`, README). The
generic part of Ch. 7 lives here; what a robot's state is, what it perceives and how its state becomes action
parameters is its TeamScene's business (tailor.sims.team).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from tailor.refinement.models.action_models import ActionModel
from tailor.refinement.models.decision_tree import DecisionTree
from tailor.sims.channel import link_states
from tailor.sims.team import Observations, Perception, TeamLog, TeamScene

STRATEGIES = ("explicit", "implicit", "shared", "distance")
NOBODY = -1  # the choice of a robot that knows no utility at all (e.g. has never seen the target)
FAILURE_FEATURES = ("time_gap", "quickest_time", "distance_gap")  # Q5's description of a situation


@dataclass(frozen=True, eq=False)
class Predictor:
    """Predicted approach times: each robot kind's learned model of its approach action (the utility)."""

    scene: TeamScene
    models: Mapping[str, ActionModel]  # action -> its duration model

    def times(self, kinds: np.ndarray, states: np.ndarray, target: np.ndarray) -> np.ndarray:
        """(M,) predicted time of robots of `kinds` (M,) in `states` (M, d) to `target` (M, 2); NaN where a state
        or the target is unknown (NaN)."""
        kinds = np.asarray(kinds)
        out = np.full(len(kinds), np.nan)
        known = np.isfinite(states).all(axis=1) & np.isfinite(target).all(axis=1)
        for kind in np.unique(kinds[known]):
            rows = known & (kinds == kind)
            params = self.scene.utility_parameters(str(kind), states[rows], target[rows])
            model = self.models[self.scene.kinds[str(kind)]]
            predicted = model.predict_duration(params)
            check = getattr(model, "check_duration", None)  # an absurd model file stops here, as in refine
            if check is not None and len(predicted):
                for extreme in (float(np.min(predicted)), float(np.max(predicted))):
                    check(extreme, f"a {kind} robot's approach")
            out[rows] = np.maximum(0.0, predicted)
        return out


# --- beliefs --------------------------------------------------------------------------------------------
def latest(valid: np.ndarray) -> np.ndarray:
    """For each tick (axis 0) the last tick at or before it where `valid` held, -1 where none did."""
    ticks = np.arange(len(valid)).reshape((-1,) + (1,) * (valid.ndim - 1))
    return np.maximum.accumulate(np.where(valid, ticks, -1), axis=0)


def _ages(index: np.ndarray, period: float) -> np.ndarray:
    ticks = np.arange(len(index)).reshape((-1,) + (1,) * (index.ndim - 1))
    return np.where(index >= 0, (ticks - index) * period, np.inf)


def most_certain(estimates: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Of (values (..., d), variance (...)) pairs, the values of the one with the least variance (the first on a
    tie), NaN where none is known."""
    best = np.full(estimates[0][0].shape, np.nan)
    least = np.full(estimates[0][1].shape, np.inf)
    for values, variance in estimates:
        better = np.isfinite(values).all(axis=-1) & (variance < least)
        best[better], least[better] = values[better], variance[better]
    return best


def fuse(estimates: list[tuple[np.ndarray, np.ndarray]], heading: int | None = None) -> np.ndarray:
    """Inverse-variance weighted mean of (values (..., d), variance (...)) pairs, NaN where none is known (an
    infinite variance or NaN values mean unknown). Component `heading` is averaged on the circle."""
    values = np.stack([v for v, _ in estimates])
    weights = np.stack([np.where(np.isfinite(var) & np.isfinite(v).all(axis=-1), 1.0 / np.maximum(var, 1e-12), 0.0)
                        for v, var in estimates])
    total = weights.sum(axis=0)
    safe = np.where(np.isfinite(values), values, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = (weights[..., None] * safe).sum(axis=0) / total[..., None]
        if heading is not None:
            s = (weights * np.sin(safe[..., heading])).sum(axis=0)
            c = (weights * np.cos(safe[..., heading])).sum(axis=0)
            out[..., heading] = np.arctan2(s, c)
    single = (weights > 0).sum(axis=0) == 1  # one estimate known: itself, exactly (no rounding)
    out[single] = np.where(weights[..., None] > 0, safe, 0.0).sum(axis=0)[single]
    out[total == 0] = np.nan
    return out


def perturbed_columns(scene: TeamScene) -> list[int]:
    """The columns of a robot's state that Q4's added estimation noise perturbs, as the scene declares them."""
    return [scene.state.index(quantity) for quantity in scene.perturbed]


@dataclass(frozen=True, eq=False)
class Beliefs:
    """Robot i's belief at tick t of the state of every robot j, (T, N, N, d) (its own estimate on the diagonal),
    and of the target, (T, N, 2); NaN where unknown."""

    states: np.ndarray
    target: np.ndarray


class Team:
    """One team log seen through one perception: the beliefs and decisions of every strategy."""

    def __init__(self, log: TeamLog, observations: Observations, perception: Perception, links: np.ndarray):
        self.log, self.obs, self.p, self.links = log, observations, perception, links
        period, p = log.period, perception
        T, N = log.states.shape[:2]
        self.kinds = np.array(log.kinds)
        # the target as each robot last perceived it itself
        index = latest(np.isfinite(observations.target[..., 0]))
        self.target_seen_at = index
        age = _ages(index, period)
        value = np.take_along_axis(observations.target, np.maximum(index, 0)[..., None], axis=0)
        self.own_target = (np.where((age <= p.target_memory)[..., None], value, np.nan),
                           p.target_noise ** 2 + (p.target_drift * age) ** 2)
        # teammates as each robot last perceived them
        index = latest(np.isfinite(observations.others[..., 0]))
        age = _ages(index, period)
        value = np.take_along_axis(observations.others, np.maximum(index, 0)[..., None], axis=0)
        self.perceived = (np.where((age <= p.memory)[..., None], value, np.nan),
                          p.teammate_noise ** 2 + (p.drift * age) ** 2)
        # the last message from each teammate: its own state estimate and its last target observation
        index = latest(links)
        age = _ages(index, period)
        fresh = age <= p.memory
        sender = np.broadcast_to(np.arange(N), (T, N, N))
        sent_at = np.maximum(index, 0)
        self.message_at, self.message_fresh = np.where(fresh, index, -1), fresh
        self.communicated = (np.where(fresh[..., None], observations.own[sent_at, sender], np.nan),
                             p.self_noise ** 2 + (p.drift * age) ** 2)
        seen_at = self.target_seen_at[sent_at, sender]
        target_age = np.where(fresh & (seen_at >= 0), (np.arange(T)[:, None, None] - seen_at) * period, np.inf)
        self.communicated_target = (
            np.where((fresh & (target_age <= p.target_memory))[..., None], self.own_target[0][sent_at, sender], np.nan),
            p.target_noise ** 2 + (p.target_drift * target_age) ** 2)

    def _with_self(self, others: np.ndarray) -> np.ndarray:
        states = others.copy()
        N = states.shape[1]
        states[:, np.arange(N), np.arange(N)] = self.obs.own
        return states

    def beliefs(self, strategy: str, extra_noise: float = 0.0, rng: np.random.Generator | None = None,
                perturbed: list[int] | None = None) -> Beliefs:
        """The beliefs perspective taking uses: `implicit` (own perception only) or `shared` (a teammate as the
        more certain of perceived and communicated, the target fused from all observations); `extra_noise` (in
        each one's unit) is added to the state columns `perturbed` (default: all) of every estimate of a
        teammate (Q4)."""
        if strategy == "implicit":
            others, target = self.perceived[0], self.own_target[0]
        elif strategy in ("shared", "distance"):
            others = most_certain([self.perceived, self.communicated])
            N = others.shape[1]
            target_estimates = [self.own_target]
            for j in range(N):  # robot i's fusion of the target observations robot j communicated
                value, variance = self.communicated_target
                target_estimates.append((value[:, :, j], variance[:, :, j]))
            target = fuse(target_estimates)
        else:
            raise ValueError(f"no beliefs for strategy {strategy!r}")
        if extra_noise > 0.0:
            if rng is None:
                raise ValueError("extra noise needs a seeded generator")
            others = others.copy()
            columns = list(range(others.shape[-1])) if perturbed is None else perturbed
            others[..., columns] += rng.standard_normal(others[..., columns].shape) * extra_noise
        return Beliefs(self._with_self(others), target)

    def utilities(self, strategy: str, predictor: Predictor, extra_noise: float = 0.0,
                  rng: np.random.Generator | None = None) -> np.ndarray:
        """(T, N, N): robot i's utility (predicted time, or distance) of robot j at each tick; NaN unknown."""
        T, N = self.log.states.shape[:2]
        if strategy == "explicit":
            own = predictor.times(np.tile(self.kinds, T), self.obs.own.reshape(-1, self.obs.own.shape[-1]),
                                  self.own_target[0].reshape(-1, 2)).reshape(T, N)
            sender = np.broadcast_to(np.arange(N), (T, N, N))
            received = np.where(self.message_fresh, own[np.maximum(self.message_at, 0), sender], np.nan)
            received[:, np.arange(N), np.arange(N)] = own
            return received
        belief = self.beliefs(strategy, extra_noise, rng, perturbed_columns(predictor.scene))
        states = belief.states.reshape(-1, belief.states.shape[-1])
        target = np.broadcast_to(belief.target[:, :, None, :], (T, N, N, 2)).reshape(-1, 2)
        if strategy == "distance":
            out = np.full(len(states), np.nan)
            known = np.isfinite(states).all(axis=1) & np.isfinite(target).all(axis=1)
            out[known] = predictor.scene.distance(states[known], target[known])
            return out.reshape(T, N, N)
        return predictor.times(np.tile(self.kinds, T * N), states, target).reshape(T, N, N)


def team_view(log: TeamLog, scene: TeamScene, perception: Perception, seed: int) -> Team:
    """The team's observations and channel for one perception; the noise and the channel's intervals follow
    from `seed` alone (the same draws for every field of view, resp. every quality's own intervals)."""
    observations = scene.observe(log, perception, np.random.default_rng([seed, 1]))
    links = link_states(log.ticks, len(log.kinds), perception.communication, perception.mean_outage, log.period,
                        np.random.default_rng([seed, 2]))
    return Team(log, observations, perception, links)


# --- decisions and their statistics -----------------------------------------------------------------------
def choices(utilities: np.ndarray) -> np.ndarray:
    """(T, N): the robot each robot thinks should go (lowest utility; the lower index on a tie), NOBODY where
    it knows none."""
    unknown = np.isnan(utilities)
    chosen = np.argmin(np.where(unknown, np.inf, utilities), axis=-1)
    return np.where(unknown.all(axis=-1), NOBODY, chosen)


def going(chosen: np.ndarray) -> np.ndarray:
    """(T,) how many robots intend to go (each chose itself)."""
    return (chosen == np.arange(chosen.shape[-1])).sum(axis=-1)


def agreed(chosen: np.ndarray) -> np.ndarray:
    """(T,) whether every robot chose the same robot (Q1)."""
    return (chosen == chosen[..., :1]).all(axis=-1) & (chosen[..., 0] != NOBODY)


def chose_quickest(chosen: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """(S, N) whether robot i chose the robot that really was quickest (Q2), per situation; measured (S, N): the
    times each robot took, inf where it failed (leave out situations where every approach failed)."""
    quickest = np.argmin(measured, axis=-1)
    return chosen == quickest[:, None]


# --- Q5: when does coordination fail? -----------------------------------------------------------------------
def failure_features(log: TeamLog, predictor: Predictor) -> np.ndarray:
    """(T, 3) the situation as the true states show it (FAILURE_FEATURES): the gap between the two lowest
    predicted times, the lowest, and the gap between the two smallest distances."""
    T, N = log.states.shape[:2]
    states = log.states.reshape(-1, log.states.shape[-1])
    target = np.repeat(log.target, N, axis=0)
    times = np.sort(predictor.times(np.tile(np.array(log.kinds), T), states, target).reshape(T, N), axis=1)
    distances = np.sort(predictor.scene.distance(states, target).reshape(T, N), axis=1)
    return np.column_stack([times[:, 1] - times[:, 0], times[:, 0], distances[:, 1] - distances[:, 0]])


@dataclass(frozen=True, eq=False)
class FailureTree:
    """Q5: a decision tree that predicts from the situation whether coordination succeeds (Fig. 7.10)."""

    tree: DecisionTree
    report: dict

    def predict_success(self, features: np.ndarray) -> np.ndarray:
        return self.tree.predict(features)


def learn_failure_tree(features: np.ndarray, success: np.ndarray, train: np.ndarray, seed: int,
                       max_depth: int = 3) -> FailureTree:
    """Fit on the rows `train` (bool), test on the others. Failures are rare, so both classes weigh the same
    (class_weight balanced): a tree that always says "success" would be accurate and useless."""
    from sklearn.tree import DecisionTreeClassifier

    from tailor.refinement.learning.classifiers import tree_arrays

    success = np.asarray(success, dtype=int)
    test = ~train
    leaf = max(20, int(0.01 * train.sum()))
    classifier = DecisionTreeClassifier(max_depth=max_depth, min_samples_leaf=leaf, class_weight="balanced",
                                        random_state=seed)
    classifier.fit(features[train], success[train])
    tree = tree_arrays(classifier).simplified()
    predicted = tree.predict(features[test]).astype(int)
    observed = success[test]
    failures = observed == 0
    report = {
        "features": list(FAILURE_FEATURES),
        "rules": tree.export_text(FAILURE_FEATURES).splitlines(),
        "train_ticks": int(train.sum()),
        "test_ticks": int(test.sum()),
        "failure_share": float(np.mean(success == 0)) if len(success) else None,
        "accuracy": float(np.mean(predicted == observed)) if test.any() else None,
        "majority_accuracy": float(max(np.mean(observed), 1 - np.mean(observed))) if test.any() else None,
        "failures_predicted": float(np.mean(predicted[failures] == 0)) if failures.any() else None,
        "successes_predicted": float(np.mean(predicted[~failures] == 1)) if (~failures).any() else None,
    }
    caught = [report["failures_predicted"], report["successes_predicted"]]
    report["balanced_accuracy"] = float(np.mean(caught)) if None not in caught else None
    return FailureTree(tree, report)
