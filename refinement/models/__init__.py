"""Action models (Chapter 4): the M5-style model tree, the decision tree, rules, the feature-space registry
(Table 4.1) and the action models stored as JSON."""
