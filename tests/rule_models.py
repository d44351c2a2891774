"""Models given by their rules (App. C.3), for optimizer tests: each predicts with the rule containing the point."""

import numpy as np
from tailor.refinement.models.rules import Rule


class RuleModel:
    """A model given by its rules (lower < x <= upper), predicting with the rule that contains the point."""

    def __init__(self, rules):
        self._rules = rules

    def rules(self):
        return self._rules

    def predict(self, F):
        F = np.atleast_2d(F)
        out = np.full(len(F), np.nan)
        for rule in self._rules:
            inside = rule.contains(F)
            out[inside] = rule.predict(F[inside])
        return out


def rule(lower, upper, coef, intercept):
    return Rule(np.array(lower, float), np.array(upper, float), np.array(coef, float), intercept)


def identity(theta):
    return np.atleast_2d(theta).copy()
