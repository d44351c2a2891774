"""The soccer simulator (pymunk): field, Pioneer-like robot with a ball guide, ball, and its actions."""

from tailor.sims.soccer.actions import ACTION_FUNCTIONS, approachBall, dribbleBall, goToPose
from tailor.sims.soccer.simulator import Noise, SoccerSim, simulate_sequence

__all__ = ["ACTION_FUNCTIONS", "Noise", "SoccerSim", "approachBall", "dribbleBall", "goToPose", "simulate_sequence"]
