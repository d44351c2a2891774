"""The dissertation's experiments as commands: refined vs greedy, horizons, the simulated optimum."""
