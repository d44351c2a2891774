"""The meta action model (Sec. 5.5.4): a decision tree predicting whether refining a situation makes its
execution better, equal or worse than greedy execution, stored as JSON (`models/meta.json`, never pickle).

It is an action model of applying action models: learned from evaluated episodes, judged by the features the
action models of the first refinement window see at the greedy parameterization and by what they predict refinement
gains there (tailor.refinement.meta_filter).
It belongs to the action models it was learned with, so it lives in their folder and is found like them
(`--models DIR`, `$TAILOR_MODELS`, the bundled folder).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tailor.errors import ModelFileError, TailorError
from tailor.refinement.models.action_models import META_FILE, read_json
from tailor.refinement.models.decision_tree import LabelTree

# what the action models predict refinement gains over greedy for the whole sequence: 1 - t_refined / t_greedy,
# and t_greedy - t_refined in seconds
REFINEMENT_FEATURES = ("refinement.predicted_gain", "refinement.predicted_seconds")
# /2 judges the window's features and refinement's predicted gain (REFINEMENT_FEATURES), /1 (still
# read) the window's features alone
META_MODEL_SCHEMA = "tailor.meta_model/2"
WINDOW_ONLY_SCHEMA = "tailor.meta_model/1"
# |1 - t_refined / t_greedy| within this counts as "equal" (Table 5.4): the meta model's labels and the better /
# equal / worse counts of `tailor evaluate` use this one tolerance
EQUAL_BAND = 0.01


@dataclass(frozen=True, eq=False)
class MetaModel:
    """Predicts better / equal / worse for refining a situation with `horizon`, from its window features."""

    window: tuple[tuple[str, str], ...]  # (executable action, feature space) of each action of the first window
    feature_names: tuple[str, ...]
    tree: LabelTree
    horizon: int  # the refinement horizon the labels compare with greedy (h = 1)
    equal_band: float  # |1 - t_refined / t_greedy| within this is "equal"
    report: dict = field(default_factory=dict)
    source: str | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        inner = self.tree.children_left != -1
        if np.any((self.tree.feature[inner] < 0) | (self.tree.feature[inner] >= len(self.feature_names))):
            raise ValueError(f"a node tests a feature outside 0..{len(self.feature_names) - 1}")

    @property
    def judges_refinement(self) -> bool:
        """Whether the features end with refinement's predicted gain (decide then needs the refined sequence)."""
        return self.feature_names[-len(REFINEMENT_FEATURES):] == REFINEMENT_FEATURES

    def predict(self, X: np.ndarray) -> np.ndarray:
        return self.tree.predict(X)

    def rules_text(self) -> str:
        return self.tree.export_text(self.feature_names)

    def to_json(self) -> dict:
        schema = META_MODEL_SCHEMA if self.judges_refinement else WINDOW_ONLY_SCHEMA
        return {"schema": schema, "horizon": self.horizon, "equal_band": self.equal_band,
                "window": [{"action": a, "feature_set": f} for a, f in self.window],
                "feature_names": list(self.feature_names), "rules": self.rules_text().splitlines(),
                "tree": self.tree.to_json(), "report": self.report}

    @classmethod
    def from_json(cls, data: dict, source: str) -> MetaModel:
        """Build from parsed JSON; anything malformed raises ModelFileError naming `source`."""
        from tailor.refinement.models.features import feature_names

        schema = data.get("schema")
        if schema not in (META_MODEL_SCHEMA, WINDOW_ONLY_SCHEMA):
            raise ModelFileError(f"schema is {schema!r}, expected {META_MODEL_SCHEMA!r} (or the older "
                                 f"{WINDOW_ONLY_SCHEMA!r})", file=source)
        horizon, band = data.get("horizon"), data.get("equal_band")
        if not isinstance(horizon, int) or isinstance(horizon, bool) or horizon < 2:
            raise ModelFileError(f"'horizon' must be an integer of at least 2, got {horizon!r}", file=source)
        if not isinstance(band, (int, float)) or isinstance(band, bool) or not 0 <= band < 1:
            raise ModelFileError(f"'equal_band' must be a number in [0, 1), got {band!r}", file=source)
        window = data.get("window")
        if (not isinstance(window, list) or not window or not all(
                isinstance(w, dict) and isinstance(w.get("action"), str) and isinstance(w.get("feature_set"), str)
                for w in window)):
            raise ModelFileError("'window' must be a non-empty list of {action, feature_set}", file=source)
        signature = tuple((w["action"], w["feature_set"]) for w in window)
        try:
            expected = tuple(f"{k + 1}.{a}.{n}" for k, (a, space) in enumerate(signature) for n in feature_names(space))
            expected += REFINEMENT_FEATURES if schema == META_MODEL_SCHEMA else ()
        except TailorError as exc:  # an unknown feature space
            raise ModelFileError(f"'window': {exc.message}", file=source) from None
        names = data.get("feature_names")
        if not isinstance(names, list) or tuple(names) != expected:
            raise ModelFileError(f"feature_names {names!r} do not match the window's feature spaces "
                                 f"{list(expected)}", file=source)
        report = data.get("report", {})
        if not isinstance(report, dict):
            raise ModelFileError("'report' must be an object", file=source)
        try:
            tree = LabelTree.from_json(data["tree"])
            return cls(signature, expected, tree, horizon, float(band), report, source)
        except (KeyError, TypeError, ValueError, OverflowError) as exc:
            raise ModelFileError(f"invalid decision tree: {exc}", file=source) from None


def meta_model_path(models_dir: Path) -> Path:
    return Path(models_dir) / META_FILE


def load_meta_model(models_dir: Path) -> MetaModel:
    """The meta model of the action models in `models_dir` (ModelFileError naming the file if it is missing or
    malformed)."""
    path = meta_model_path(models_dir)
    if not path.is_file():
        raise ModelFileError("no meta action model here: the filter needs one (learn it with `tailor evaluate "
                             "DOMAIN --meta`)", file=str(path))
    return MetaModel.from_json(read_json(path), str(path))
