"""Experience -> action models (Chapter 4): the duration protocol (Fig. 4.9), classifiers, training recipes,
subgoal experience, reports and learning plots."""
